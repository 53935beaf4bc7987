//! What a device backend is: the contract each vendor's file fills in, and what opening one
//! takes and gives. The list of backends is [`super::Registry`]'s.

use capture::CaptureKind;
use sim::{HandImpedance, HandScript};

use super::sim_world::{SimOmega7Config, SimWorld};
use super::{DeviceSpecs, HapticDevice};
use crate::error::HapticsError;

/// What moves the tool.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Motion {
    /// The operator's hand (a real one on the handle, or the simulated one), under the forces
    /// the loop commands.
    Operator,
    /// A recording: the device plays recorded motion and the forces go nowhere, so a session
    /// renders the law straight from the played position and a protocol cannot drive it.
    Recorded,
}

/// The option a backend takes after its name (`NAME:OPTION`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BackendOption {
    /// What it is, as `--help` shows it (`PATH`, `FILE`).
    pub value_name: &'static str,
    /// What it means.
    pub help: &'static str,
    /// Whether the backend cannot open without it.
    pub required: bool,
}

/// The simulated world and hand a simulated backend opens onto; other backends ignore it.
pub struct SimSetup {
    /// The mechanism and where it starts.
    pub config: SimOmega7Config,
    /// What the tool touches.
    pub world: SimWorld,
    /// The operator's hand, if one holds the handle, and when its script ends, s.
    pub hand: Option<(HandImpedance, Box<dyn HandScript>, Option<f64>)>,
}

/// What opening a device takes.
#[derive(Debug)]
pub struct OpenRequest<'a> {
    /// The haptic loop's period, s.
    pub period_s: f64,
    /// The option given after the name.
    pub option: Option<&'a str>,
    /// The world, for a simulated backend.
    pub sim: SimSetup,
    /// The kind of capture a recording must be to stand in for this task.
    pub recording_kind: CaptureKind,
}

/// An opened device and when it stops moving by itself (a replay's end, a scripted hand's), s.
pub struct OpenedDevice {
    /// The device, forces off.
    pub device: Box<dyn HapticDevice>,
    /// When the motion it plays ends, s from its start; `None` for an operator's hand.
    pub script_end_s: Option<f64>,
}

/// One vendor's device, or a stand-in for one: its name, specs, option, and how it is found and
/// opened.
#[derive(Debug)]
pub struct Backend {
    /// The name scenes and `--device` use (`sim`, `omega7`, `replay`).
    pub name: &'static str,
    /// What it is, in a line.
    pub summary: &'static str,
    /// Its limits and geometry: every force command and every scene bound is checked against
    /// them.
    pub specs: DeviceSpecs,
    /// The option it takes after its name, if any.
    pub option: Option<BackendOption>,
    /// Whether it simulates its world, so that a loop may run it faster than real time and a
    /// scene's simulated surfaces exist for it.
    pub simulated: bool,
    /// What moves its tool.
    pub motion: Motion,
    /// Opens it.
    pub open: fn(OpenRequest<'_>) -> Result<OpenedDevice, HapticsError>,
    /// Looks for it without opening it: one line per finding, for `palpus devices`.
    pub probe: fn(Option<&str>) -> Vec<String>,
}

impl PartialEq for Backend {
    fn eq(&self, other: &Self) -> bool {
        self.name == other.name
    }
}

// By hand: a hand script and a device are trait objects without `Debug`; their names say enough.
impl std::fmt::Debug for SimSetup {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SimSetup")
            .field("config", &self.config)
            .field("world", &self.world)
            .field(
                "hand",
                &self.hand.as_ref().map(|(impedance, _, end_s)| (impedance, end_s)),
            )
            .finish()
    }
}

impl std::fmt::Debug for OpenedDevice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("OpenedDevice")
            .field("device", &self.device.name())
            .field("script_end_s", &self.script_end_s)
            .finish()
    }
}

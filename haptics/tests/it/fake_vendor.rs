//! A vendor added in one file: a backend with its own name, option, specs and opener, added to
//! the registry with one call, is chosen by name, opened, run by the haptic loop within its own
//! force limit, and named in every refusal.

use std::sync::Arc;

use capture::CaptureKind;
use glam::DVec3;
use haptics::HapticsError;
use haptics::rt::{Controller, TickInput, TickOutput};
use haptics::{
    Backend, BackendOption, DeviceSpecs, DeviceState, ForceCommand, ForceGate, ForceOverride, HapticDevice,
    InternalForces, Motion, OpenRequest, OpenedDevice, Registry, SimSetup,
};
use haptics::{SimOmega7Config, SimWorld};

use crate::common::run_unpaced;

/// A small desktop device: 3 N, a 60 mm workspace.
const FAKE_SPECS: DeviceSpecs = DeviceSpecs {
    model: "Fake Desk 3",
    max_force_n: 3.0,
    max_gripper_force_n: 0.0,
    workspace_radius_m: 0.06,
    max_gripper_gap_m: 0.0,
    max_stiffness_npm: 1000.0,
    max_damping_nspm: 5.0,
    internal: InternalForces::NONE,
};

static FAKE: Backend = Backend {
    name: "fakedesk",
    summary: "Fake Desk 3",
    specs: FAKE_SPECS,
    option: Some(BackendOption {
        value_name: "SERIAL",
        help: "which unit",
        required: true,
    }),
    simulated: false,
    motion: Motion::Operator,
    open: open_fake,
    probe: |serial| vec![format!("unit {}", serial.unwrap_or("?"))],
};

// The backend contract returns the crate's error, as every vendor's opener does.
#[allow(clippy::result_large_err)]
fn open_fake(request: OpenRequest<'_>) -> Result<OpenedDevice, HapticsError> {
    let serial = request.option.unwrap_or_default();
    if serial != "42" {
        return Err(HapticsError::NoDevice {
            device: "Fake Desk",
            detail: format!("no Fake Desk with serial {serial}"),
        });
    }
    Ok(OpenedDevice {
        device: Box::new(FakeDesk {
            period_s: request.period_s,
            tick: 0,
            gate: Arc::new(ForceGate::new()),
            last: ForceCommand::ZERO,
            forces: false,
        }),
        script_end_s: None,
    })
}

/// Keeps the last command it was sent.
#[derive(Debug)]
struct FakeDesk {
    period_s: f64,
    tick: u64,
    gate: Arc<ForceGate>,
    last: ForceCommand,
    forces: bool,
}

impl HapticDevice for FakeDesk {
    fn specs(&self) -> &DeviceSpecs {
        &FAKE_SPECS
    }
    fn name(&self) -> &str {
        "fakedesk"
    }
    fn enable_forces(&mut self, enabled: bool) -> Result<(), HapticsError> {
        self.forces = enabled;
        Ok(())
    }
    fn read_state(&mut self) -> Result<DeviceState, HapticsError> {
        self.tick += 1;
        Ok(DeviceState {
            time_s: self.tick as f64 * self.period_s,
            ..DeviceState::default()
        })
    }
    fn command(&mut self, command: &ForceCommand) -> Result<(), HapticsError> {
        self.last = self.gate.pass(command);
        Ok(())
    }
    fn force_override(&self) -> Arc<dyn ForceOverride> {
        self.gate.clone()
    }
    fn close(&mut self) -> Result<(), HapticsError> {
        Ok(())
    }
}

/// Asks for 50 N along +x every tick.
struct Push;

impl Controller for Push {
    fn tick(&mut self, _: &TickInput<'_>, output: &mut TickOutput) {
        output.command.force_n = DVec3::new(50.0, 0.0, 0.0);
    }
}

fn no_world() -> SimSetup {
    SimSetup {
        config: SimOmega7Config::default(),
        world: SimWorld::Free,
        hand: None,
    }
}

#[test]
fn a_vendor_in_one_file_is_chosen_opened_and_held_to_its_own_limit() {
    let registry = Registry::builtin().with(&FAKE);
    assert!(
        registry.names().ends_with("fakedesk:SERIAL"),
        "{}",
        registry.names()
    );
    assert_eq!((FAKE.probe)(Some("42")), ["unit 42"]);

    let choice = registry.choose("fakedesk:42").unwrap();
    assert_eq!(choice.label(), "Fake Desk 3 (42)");
    let mut opened = choice.open(1e-3, no_world(), CaptureKind::Insertion).unwrap();
    assert_eq!(opened.device.specs().model, "Fake Desk 3");
    let samples = run_unpaced(&mut opened.device, &mut Push, 50);
    assert_eq!(samples.len(), 50);
    for s in &samples {
        assert!(
            s.command.force_n.length() <= FAKE_SPECS.max_force_n + 1e-12,
            "{:?}",
            s.command
        );
    }
    assert!((samples[49].command.force_n.x - FAKE_SPECS.max_force_n).abs() < 1e-12);

    let absent = registry.choose("fakedesk:7").unwrap();
    let e = absent.open(1e-3, no_world(), CaptureKind::Insertion).unwrap_err();
    assert!(e.to_string().contains("serial 7"), "{e}");
    let e = registry.choose("fakedesk").unwrap_err().to_string();
    assert!(
        e.contains("needs its SERIAL") && e.contains("fakedesk:SERIAL"),
        "{e}"
    );
    // The builtin list is untouched by another program's addition.
    assert!(Registry::builtin().get("fakedesk").is_none());
}

//! A simulated Omega.7: what the haptic loop meets when there is no hardware.
//!
//! Per axis the end effector is a mass (Nakano's nominal 0.3 kg) driven by the actuators,
//! the operator's hand ([`sim::HandScript`]), the world it touches, and the mechanism's own
//! viscous and Coulomb friction. Actuator force saturates at the device's 12 N (gripper 8 N).
//! The device reports what the real one reports: the position through the Omega.7's 10 µm
//! encoder quantization and a velocity estimated from that quantized position (Li & Bi's
//! pseudo-differentiation) — no force sensor. Physics runs in sub-steps of the loop period so
//! that stiff contact stays accurate.
//!
//! The world is the foundation's ground truth: needle insertion into layered tissue
//! ([`NeedleSite`](sim::NeedleSite)) along −z, or a horizontal surface (Li & Bi's hard and soft contacts, or one
//! of Nakano's textured patches, [`SurfacePatch`](sim::SurfacePatch)) under the tip.

use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::DVec3;

use super::backend::{Backend, Motion, OpenRequest, OpenedDevice, SimSetup};
pub use super::sim_world::{SimOmega7Config, SimWorld, Texture};
use super::{
    DeviceSpecs, DeviceState, ForceCommand, ForceGate, ForceOverride, HapticDevice, HardwareWatchdog,
};
use crate::error::HapticsError;
use capture::PseudoDifferentiator;
use sim::Encoder;
use sim::{HandImpedance, HandScript};

/// The simulated Omega.7 in the device registry.
pub static BACKEND: Backend = Backend {
    name: "sim",
    summary: "simulated Omega.7",
    specs: DeviceSpecs::OMEGA7,
    option: None,
    simulated: true,
    motion: Motion::Operator,
    open,
    probe: |_| vec!["always available: the Omega.7's mechanism and sensors over the simulated world".into()],
};

fn open(request: OpenRequest<'_>) -> Result<OpenedDevice, HapticsError> {
    let SimSetup { config, world, hand } = request.sim;
    let config = SimOmega7Config {
        period_s: request.period_s,
        ..config
    };
    let device = SimOmega7::new(config, world);
    Ok(match hand {
        Some((impedance, script, script_end_s)) => OpenedDevice {
            device: Box::new(device.with_hand(impedance, script)),
            script_end_s,
        },
        None => OpenedDevice {
            device: Box::new(device),
            script_end_s: None,
        },
    })
}

/// One physics record, for tests and diagnostics (see [`SimOmega7::with_trace`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SimTrace {
    /// Device time at the end of the period, s.
    pub time_s: f64,
    /// True position, m.
    pub position_m: DVec3,
    /// True velocity, m/s.
    pub velocity_mps: DVec3,
    /// Force of the hand on the end effector (what the operator feels, reversed), N.
    pub hand_force_n: DVec3,
    /// Force of the world on the end effector, N.
    pub world_force_n: DVec3,
    /// Actuator force after saturation and the force gate, N.
    pub actuator_force_n: DVec3,
    /// Hand target position, m.
    pub hand_target_m: DVec3,
}

/// The simulated Omega.7.
pub struct SimOmega7 {
    config: SimOmega7Config,
    specs: DeviceSpecs,
    world: SimWorld,
    hand: Option<(HandImpedance, Box<dyn HandScript>)>,
    gate: Arc<ForceGate>,
    forces_enabled: bool,
    closed: bool,
    tick: u64,
    time_s: f64,
    x: DVec3,
    v: DVec3,
    gap_m: f64,
    gap_v: f64,
    encoder: Encoder,
    velocity: [PseudoDifferentiator; 3],
    measured: DeviceState,
    last_hand_force_n: DVec3,
    last_world_force_n: DVec3,
    last_actuator_n: f64,
    trace: Vec<SimTrace>,
    trace_capacity: usize,
    watchdog: Option<SimWatchdog>,
}

/// The Omega.7's own watchdog as the simulator models it: it sees the host's commands arrive
/// on its own clock (the wall clock here: a stalled host stalls the simulation with it, but
/// not the device's firmware), and a silence longer than its period would have released the
/// force the device was holding.
#[derive(Debug, Clone, Copy)]
struct SimWatchdog {
    period: Duration,
    last_command: Option<Instant>,
    /// The force norm the actuators applied after the last command, N: what they hold while
    /// no command comes.
    holding_n: f64,
    longest_gap: Option<(Duration, f64)>,
    trips: u32,
}

impl std::fmt::Debug for SimOmega7 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SimOmega7")
            .field("config", &self.config)
            .field("tick", &self.tick)
            .field("position_m", &self.x)
            .finish_non_exhaustive()
    }
}

impl SimOmega7 {
    /// A device in `world`, untouched by any hand.
    pub fn new(config: SimOmega7Config, world: SimWorld) -> Self {
        let dt = config.period_s;
        let mut device = Self {
            config,
            specs: DeviceSpecs::OMEGA7,
            world,
            hand: None,
            gate: Arc::new(ForceGate::new()),
            forces_enabled: false,
            closed: false,
            tick: 0,
            time_s: 0.0,
            x: config.start_m,
            v: DVec3::ZERO,
            gap_m: 0.01,
            gap_v: 0.0,
            encoder: Encoder {
                quantum_m: config.encoder_quantum_m,
            },
            velocity: [PseudoDifferentiator::new(dt, config.velocity_tau_s); 3],
            measured: DeviceState::default(),
            last_hand_force_n: DVec3::ZERO,
            last_world_force_n: DVec3::ZERO,
            last_actuator_n: 0.0,
            trace: Vec::new(),
            trace_capacity: 0,
            watchdog: None,
        };
        device.measure();
        device
    }

    /// Adds an operator's hand holding the end effector.
    pub fn with_hand(mut self, impedance: HandImpedance, script: Box<dyn HandScript>) -> Self {
        self.hand = Some((impedance, script));
        self
    }

    /// Keeps a physics record of the first `capacity` periods (allocated now, so recording
    /// does not allocate on the haptic thread).
    pub fn with_trace(mut self, capacity: usize) -> Self {
        self.trace = Vec::with_capacity(capacity);
        self.trace_capacity = capacity;
        self
    }

    /// The physics record.
    pub fn trace(&self) -> &[SimTrace] {
        &self.trace
    }

    /// The world.
    pub fn world(&self) -> &SimWorld {
        &self.world
    }

    /// True position and velocity.
    pub fn true_state(&self) -> (DVec3, DVec3) {
        (self.x, self.v)
    }

    /// Force of the hand on the end effector during the last period, N.
    pub fn hand_force_n(&self) -> DVec3 {
        self.last_hand_force_n
    }

    /// Force of the world on the end effector during the last period, N.
    pub fn world_force_n(&self) -> DVec3 {
        self.last_world_force_n
    }

    /// The configuration.
    pub fn config(&self) -> &SimOmega7Config {
        &self.config
    }

    fn measure(&mut self) {
        let p = DVec3::new(
            self.encoder.read(self.x.x),
            self.encoder.read(self.x.y),
            self.encoder.read(self.x.z),
        );
        let v = DVec3::new(
            self.velocity[0].update(p.x),
            self.velocity[1].update(p.y),
            self.velocity[2].update(p.z),
        );
        self.measured = DeviceState {
            time_s: self.time_s,
            position_m: p,
            velocity_mps: v,
            gripper_gap_m: self.encoder.read(self.gap_m),
            buttons: 0,
        };
    }

    fn step(&mut self, command: &ForceCommand) {
        let c = self.config;
        let n = c.substeps.max(1);
        let dt = c.period_s / f64::from(n);
        let max_f = self.specs.max_force_n;
        let mut actuator = if self.forces_enabled {
            self.gate.pass(command)
        } else {
            self.gate.pass(&ForceCommand::ZERO)
        };
        // Actuator saturation: the amplifiers deliver at most 12 N (8 N on the gripper).
        let norm = actuator.force_n.length();
        if norm.is_nan() || norm > max_f {
            actuator.force_n = if norm.is_finite() && norm > 0.0 {
                actuator.force_n * (max_f / norm)
            } else {
                DVec3::ZERO
            };
        }
        let max_g = self.specs.max_gripper_force_n;
        actuator.gripper_force_n = if actuator.gripper_force_n.is_finite() {
            actuator.gripper_force_n.clamp(-max_g, max_g)
        } else {
            0.0
        };
        let mut hand_sum = DVec3::ZERO;
        let mut world_sum = DVec3::ZERO;
        let mut target_m = DVec3::ZERO;
        for k in 0..n {
            let t = self.time_s + f64::from(k) * dt;
            let (hand, gap_target) = match &mut self.hand {
                Some((imp, script)) => {
                    let target = script.target(t);
                    target_m = target.position_m;
                    (
                        imp.stiffness_npm * (target.position_m - self.x)
                            + imp.damping_nspm * (target.velocity_mps - self.v),
                        Some(target.gripper_gap_m),
                    )
                }
                None => (DVec3::ZERO, None),
            };
            let world = self.world.force(self.x, self.v, dt);
            let band = 1e-3;
            let internal = -(c.viscous_nspm * self.v
                + c.coulomb_n
                    * DVec3::new(
                        (self.v.x / band).tanh(),
                        (self.v.y / band).tanh(),
                        (self.v.z / band).tanh(),
                    ));
            // The workspace ends in mechanical stops.
            let r = self.x.length();
            let stop = if r > self.specs.workspace_radius_m {
                -self.x / r * 5000.0 * (r - self.specs.workspace_radius_m)
            } else {
                DVec3::ZERO
            };
            let a = (actuator.force_n + hand + world + internal + stop) / c.mass_kg;
            self.v += a * dt;
            self.x += self.v * dt;
            hand_sum += hand;
            world_sum += world;
            // The gripper: 50 g of finger and blade, fingers as a 50 N/m spring to their aim.
            let finger = gap_target.map_or(0.0, |g| 50.0 * (g - self.gap_m) - 1.0 * self.gap_v);
            self.gap_v += (actuator.gripper_force_n + finger - 0.5 * self.gap_v) / 0.05 * dt;
            self.gap_m += self.gap_v * dt;
            if self.gap_m < 0.0 || self.gap_m > self.specs.max_gripper_gap_m {
                self.gap_m = self.gap_m.clamp(0.0, self.specs.max_gripper_gap_m);
                self.gap_v = 0.0;
            }
        }
        if !(self.x.is_finite() && self.v.is_finite()) {
            // Never reached with saturated inputs; if it were, a stopped device is the honest
            // state.
            self.x = self.config.start_m;
            self.v = DVec3::ZERO;
        }
        self.last_hand_force_n = hand_sum / f64::from(n);
        self.last_world_force_n = world_sum / f64::from(n);
        self.last_actuator_n = actuator.force_n.length();
        self.time_s += c.period_s;
        if self.trace.len() < self.trace_capacity {
            self.trace.push(SimTrace {
                time_s: self.time_s,
                position_m: self.x,
                velocity_mps: self.v,
                hand_force_n: self.last_hand_force_n,
                world_force_n: self.last_world_force_n,
                actuator_force_n: actuator.force_n,
                hand_target_m: target_m,
            });
        }
        self.measure();
    }
}

impl HapticDevice for SimOmega7 {
    fn specs(&self) -> &DeviceSpecs {
        &self.specs
    }

    fn name(&self) -> &str {
        "sim-omega7"
    }

    fn enable_forces(&mut self, enabled: bool) -> Result<(), HapticsError> {
        if self.closed {
            return Err(HapticsError::DeviceClosed { tick: None });
        }
        self.forces_enabled = enabled;
        Ok(())
    }

    fn read_state(&mut self) -> Result<DeviceState, HapticsError> {
        if self.closed {
            return Err(HapticsError::DeviceClosed { tick: None });
        }
        if self.config.fail_after_ticks.is_some_and(|n| self.tick >= n) {
            return Err(HapticsError::DeviceFault {
                what: "simulated USB disconnect",
                tick: None,
            });
        }
        Ok(self.measured)
    }

    fn command(&mut self, command: &ForceCommand) -> Result<(), HapticsError> {
        if self.closed {
            return Err(HapticsError::DeviceClosed { tick: None });
        }
        if let Some(w) = self.watchdog.as_mut() {
            let now = Instant::now();
            if let Some(last) = w.last_command {
                let gap = now.saturating_duration_since(last);
                if w.longest_gap.is_none_or(|(g, _)| gap > g) {
                    w.longest_gap = Some((gap, w.holding_n));
                }
                if gap > w.period {
                    w.trips += 1;
                }
            }
            w.last_command = Some(now);
        }
        self.step(command);
        if let Some(w) = self.watchdog.as_mut() {
            w.holding_n = self.last_actuator_n;
        }
        self.tick += 1;
        Ok(())
    }

    fn force_override(&self) -> Arc<dyn ForceOverride> {
        self.gate.clone()
    }

    fn close(&mut self) -> Result<(), HapticsError> {
        self.forces_enabled = false;
        self.gate.pass(&ForceCommand::ZERO);
        self.closed = true;
        Ok(())
    }

    /// Modelled on the Omega.7's: 125 µs steps, up to 255 of them.
    fn arm_watchdog(&mut self, period: Duration) -> Result<Option<Duration>, HapticsError> {
        if self.closed {
            return Err(HapticsError::DeviceClosed { tick: None });
        }
        let period = super::WATCHDOG_STEP * u32::from(super::watchdog_steps(period));
        self.watchdog = Some(SimWatchdog {
            period,
            last_command: None,
            holding_n: 0.0,
            longest_gap: None,
            trips: 0,
        });
        Ok(Some(period))
    }

    fn hardware_watchdog(&self) -> Option<HardwareWatchdog> {
        self.watchdog.map(|w| HardwareWatchdog {
            period: w.period,
            longest_gap: w.longest_gap,
            trips: Some(w.trips),
        })
    }
}

impl SimOmega7 {
    /// The gate the watchdog acts on; its `applied()` is what the actuators apply now.
    pub fn gate(&self) -> &Arc<ForceGate> {
        &self.gate
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn its_own_watchdog_sees_a_silence_of_the_host_and_what_it_held() {
        let mut d = SimOmega7::new(SimOmega7Config::default(), SimWorld::Free);
        assert_eq!(d.hardware_watchdog(), None);
        // 4 ms is 32 steps of 125 µs; 4.01 ms rounds up to 33.
        assert_eq!(
            d.arm_watchdog(Duration::from_micros(4010)).unwrap(),
            Some(Duration::from_micros(4125))
        );
        d.arm_watchdog(Duration::from_millis(4)).unwrap();
        d.enable_forces(true).unwrap();
        let push = ForceCommand {
            force_n: DVec3::new(0.0, 0.0, 3.0),
            gripper_force_n: 0.0,
        };
        d.command(&push).unwrap();
        std::thread::sleep(Duration::from_millis(30));
        d.command(&push).unwrap();
        let w = d.hardware_watchdog().unwrap();
        assert_eq!((w.period, w.trips), (Duration::from_millis(4), Some(1)));
        let (gap, held) = w.longest_gap.unwrap();
        assert!(
            gap >= Duration::from_millis(30) && (held - 3.0).abs() < 1e-12,
            "{gap:?} {held}"
        );
    }
    use sim::{NeedleSite, NeedleTissue};

    #[test]
    fn a_constant_force_accelerates_the_mass_and_saturates_at_12_n() {
        let mut d = SimOmega7::new(
            SimOmega7Config {
                viscous_nspm: 0.0,
                coulomb_n: 0.0,
                ..SimOmega7Config::default()
            },
            SimWorld::Free,
        );
        d.enable_forces(true).unwrap();
        let push = ForceCommand {
            force_n: DVec3::new(0.0, 0.0, 0.3),
            gripper_force_n: 0.0,
        };
        for _ in 0..100 {
            d.command(&push).unwrap();
        }
        // a = 1 m/s², 0.1 s: v = 0.1 m/s, x = 5 mm.
        let (x, v) = d.true_state();
        assert!((v.z - 0.1).abs() < 1e-9 && (x.z - 0.005).abs() < 1e-4, "{x} {v}");
        let s = d.read_state().unwrap();
        // Quantized to 10 µm, velocity estimated.
        assert_eq!(s.position_m.z, (x.z * 1e5).round() / 1e5);
        assert!((s.velocity_mps.z - 0.1).abs() < 0.01, "{}", s.velocity_mps.z);
        let mut fresh = SimOmega7::new(SimOmega7Config::default(), SimWorld::Free);
        fresh.enable_forces(true).unwrap();
        fresh
            .command(&ForceCommand {
                force_n: DVec3::new(100.0, 0.0, 0.0),
                gripper_force_n: 0.0,
            })
            .unwrap();
        assert!(fresh.trace().is_empty());
        assert!((fresh.true_state().1.x - 12.0 / 0.3 * 1e-3).abs() < 1e-3);
    }

    #[test]
    fn forces_are_off_until_enabled_and_the_gate_scales_them() {
        let mut d = SimOmega7::new(SimOmega7Config::default(), SimWorld::Free);
        let push = ForceCommand {
            force_n: DVec3::X,
            gripper_force_n: 0.0,
        };
        d.command(&push).unwrap();
        assert_eq!(d.true_state().1, DVec3::ZERO);
        d.enable_forces(true).unwrap();
        d.force_override().set_force_scale(0.0);
        d.command(&push).unwrap();
        assert_eq!(d.true_state().1, DVec3::ZERO);
        d.close().unwrap();
        assert!(matches!(
            d.read_state(),
            Err(HapticsError::DeviceClosed { tick: None })
        ));
    }

    #[test]
    fn pushing_the_needle_down_meets_the_tissue() {
        let world = SimWorld::needle(NeedleSite::new(NeedleTissue::bovine_liver()), 0.0);
        let mut d = SimOmega7::new(
            SimOmega7Config {
                start_m: DVec3::new(0.0, 0.0, 0.001),
                ..SimOmega7Config::default()
            },
            world,
        );
        d.enable_forces(true).unwrap();
        // Push down firmly for a while: the tissue pushes back, then ruptures.
        let mut peak: f64 = 0.0;
        for _ in 0..2000 {
            d.command(&ForceCommand {
                force_n: DVec3::new(0.0, 0.0, -2.5),
                gripper_force_n: 0.0,
            })
            .unwrap();
            peak = peak.max(d.world_force_n().z);
        }
        assert!(d.world().needle_site(0.0).unwrap().punctured() >= 1);
        assert!(peak > 0.9, "{peak}");
    }
}

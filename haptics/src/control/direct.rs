//! Direct (impedance) rendering: the environment's force at the device's own position, for
//! devices that only report motion, such as a replayed capture, where admittance has nothing
//! to move.

use super::admittance::channel;
use crate::law::Environment;
use crate::rt::{CHANNELS, Controller, TickInput, TickOutput};

/// Renders an environment `E` at the device's position. Its samples use the admittance
/// renderer's channel layout ([`channel`]), the device standing in for the virtual tool.
#[derive(Debug)]
pub struct Direct<E>(E);

impl<E> Direct<E> {
    /// Renders `environment`.
    pub fn new(environment: E) -> Self {
        Self(environment)
    }
}

impl<E: Environment> Controller for Direct<E> {
    fn tick(&mut self, input: &TickInput<'_>, out: &mut TickOutput) {
        let s = input.state;
        let env = self.0.force(s.position_m, s.velocity_mps);
        out.command.force_n = env.force_n;
        out.flags |= env.flags;
        out.channels = [0.0; CHANNELS];
        out.channels[channel::HAND_FORCE_Z_N] = -env.force_n.z;
        out.channels[channel::MODEL_FORCE_Z_N] = env.force_n.z;
        out.channels[channel::VIRTUAL_Z_M] = s.position_m.z;
        out.channels[channel::VIRTUAL_VZ_MPS] = s.velocity_mps.z;
        out.channels[channel::ENV_STATE] = env.state;
        out.channels[channel::ENV_INPUT] = env.input;
        out.channels[channel::HAND_FORCE_X_N] = -env.force_n.x;
        out.channels[channel::MODEL_FORCE_X_N] = env.force_n.x;
    }
}

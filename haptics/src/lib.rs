//! The haptic side of palpus.
//!
//! Today this crate holds the simulated world: ground-truth tissue, friction and surface physics
//! seen through realistic sensor models, and the measurement protocols of the three papers that
//! turn that world into captures. The same world later drives the simulated Omega.7.

pub mod sim;

//! Control: observers (DOB, RFOB), acceleration-based motion and force control, admittance
//! and direct rendering, and the rubbing controller.

pub mod admittance;
pub mod direct;
pub mod motion;
pub mod observer;
pub mod rubbing;

pub use admittance::{Admittance, AdmittanceConfig};
pub use direct::Direct;
pub use motion::{AccelerationControl, MotionGains};
pub use observer::{DisturbanceObserver, Observed, Observers3, ReactionForceObserver};
pub use rubbing::{RubbingController, RubbingPhase, RubbingPlan};

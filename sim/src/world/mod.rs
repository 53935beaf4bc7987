//! The simulated world, in SI units.
//!
//! Each module holds one piece of ground-truth physics, with the equation it implements and
//! where that equation (and its numbers) come from. Nothing here knows about files: the
//! protocols in [`super::protocols`] sample this world through [`sensor`] models into captures.

pub mod friction;
pub mod needle;
pub mod profile;
pub mod scratch;
pub mod sensor;
pub mod surface;

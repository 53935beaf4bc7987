//! Units of foreign columns: what a suffix measures and its factor to SI.

use super::*;

/// What a column measures, from its unit suffix.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    /// Seconds (`_s`).
    Time,
    /// Metres (`_m`).
    Length,
    /// Newtons (`_n`).
    Force,
    /// Metres per second (`_mps`).
    Velocity,
    /// Metres per second squared (`_mps2`).
    Acceleration,
}

impl Quantity {
    /// The quantity a capture column measures, from its suffix.
    pub fn of_column(name: &str) -> Option<Self> {
        // `_mps2` before `_mps`; `_s` cannot match `_mps` (no underscore before the `s`).
        [
            ("_mps2", Quantity::Acceleration),
            ("_mps", Quantity::Velocity),
            ("_s", Quantity::Time),
            ("_m", Quantity::Length),
            ("_n", Quantity::Force),
        ]
        .into_iter()
        .find(|(suffix, _)| name.ends_with(suffix))
        .map(|(_, q)| q)
    }

    /// The SI unit.
    pub fn si_unit(self) -> &'static str {
        match self {
            Quantity::Time => "s",
            Quantity::Length => "m",
            Quantity::Force => "N",
            Quantity::Velocity => "m/s",
            Quantity::Acceleration => "m/s2",
        }
    }
}

impl fmt::Display for Quantity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Quantity::Time => "time",
            Quantity::Length => "length",
            Quantity::Force => "force",
            Quantity::Velocity => "velocity",
            Quantity::Acceleration => "acceleration",
        })
    }
}

/// Standard gravity, m/s², for the `g` unit.
pub const STANDARD_GRAVITY_MPS2: f64 = 9.806_65;

/// `(unit, quantity, multiply, divide)`: SI value = value × multiply / divide. Decimal
/// sub-units divide by an exact power of ten (0.001 is not exact in binary, 1000 is), so a
/// value written in mm converts to the correctly rounded value in m.
pub(super) const UNITS: &[(&str, Quantity, f64, f64)] = &[
    ("s", Quantity::Time, 1.0, 1.0),
    ("ms", Quantity::Time, 1.0, 1e3),
    ("us", Quantity::Time, 1.0, 1e6),
    ("µs", Quantity::Time, 1.0, 1e6),
    ("μs", Quantity::Time, 1.0, 1e6),
    ("m", Quantity::Length, 1.0, 1.0),
    ("cm", Quantity::Length, 1.0, 1e2),
    ("mm", Quantity::Length, 1.0, 1e3),
    ("um", Quantity::Length, 1.0, 1e6),
    ("µm", Quantity::Length, 1.0, 1e6),
    ("μm", Quantity::Length, 1.0, 1e6),
    ("N", Quantity::Force, 1.0, 1.0),
    ("mN", Quantity::Force, 1.0, 1e3),
    ("kN", Quantity::Force, 1e3, 1.0),
    ("m/s", Quantity::Velocity, 1.0, 1.0),
    ("cm/s", Quantity::Velocity, 1.0, 1e2),
    ("mm/s", Quantity::Velocity, 1.0, 1e3),
    ("m/s2", Quantity::Acceleration, 1.0, 1.0),
    ("m/s^2", Quantity::Acceleration, 1.0, 1.0),
    ("mm/s2", Quantity::Acceleration, 1.0, 1e3),
    ("mm/s^2", Quantity::Acceleration, 1.0, 1e3),
    ("g", Quantity::Acceleration, STANDARD_GRAVITY_MPS2, 1.0),
];

/// The unit table: what `unit` measures and its size in SI units (`mm` → `(Length, 1e-3)`,
/// `g` → `(Acceleration, 9.80665)`), or `None` for an unknown unit. Unit names are
/// case-sensitive (`mN` is a millinewton, `MN` is not known); `µ` and `u` both mean micro.
pub fn unit_to_si(unit: &str) -> Option<(Quantity, f64)> {
    unit_scale(unit).map(|(q, s)| (q, s.factor()))
}

pub(super) fn unit_scale(unit: &str) -> Option<(Quantity, Scale)> {
    UNITS
        .iter()
        .find(|(name, ..)| *name == unit)
        .map(|&(_, q, mul, div)| (q, Scale { mul, div }))
}

pub(super) fn units_of(quantity: Quantity) -> String {
    let names: Vec<&str> = UNITS
        .iter()
        .filter(|(name, q, ..)| *q == quantity && name.is_ascii())
        .map(|(name, ..)| *name)
        .collect();
    names.join(", ")
}

/// A conversion to SI: `value × mul / div`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scale {
    pub(super) mul: f64,
    pub(super) div: f64,
}

impl Scale {
    /// No conversion.
    pub const IDENTITY: Scale = Scale { mul: 1.0, div: 1.0 };

    /// Converts one value.
    pub fn apply(self, value: f64) -> f64 {
        value * self.mul / self.div
    }

    /// The overall factor (SI value per input value).
    pub fn factor(self) -> f64 {
        self.mul / self.div
    }
}

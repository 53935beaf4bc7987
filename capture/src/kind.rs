//! Capture kinds and the columns each kind may carry.
//!
//! This is the single place that says which columns exist. Every column name
//! carries its SI unit as a suffix (`_s`, `_m`, `_n`, `_mps`, `_mps2`) so a
//! file is self-describing without a side table of units.

use std::fmt;
use std::str::FromStr;

/// What was recorded: a tool rubbing over a surface, or a needle going into tissue.
///
/// The kind decides which columns a capture must and may have (see
/// [`CaptureKind::required_columns`] and [`CaptureKind::optional_columns`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CaptureKind {
    /// A tool tip sliding tangentially over a surface under a normal load;
    /// used to identify friction and texture.
    Rubbing,
    /// A needle pushed along its axis into tissue; used to identify the
    /// axial force-depth-velocity relation.
    Insertion,
}

/// Sample time since the start of the recording, in seconds. Always the
/// first column, strictly increasing.
pub const TIME_S: &str = "time_s";

// --- Rubbing columns -------------------------------------------------------

/// Tool position along the sliding direction, in metres.
pub const TANGENTIAL_POSITION_M: &str = "tangential_position_m";
/// Normal load pressing the tool onto the surface, in newtons (positive
/// when pressing into the surface).
pub const NORMAL_FORCE_N: &str = "normal_force_n";
/// Measured tool velocity along the sliding direction, in m/s (same sign
/// convention as `tangential_position_m`).
pub const TANGENTIAL_VELOCITY_MPS: &str = "tangential_velocity_mps";
/// Velocity the protocol/controller asked for, in m/s. For rubbing it is
/// along the sliding direction; for insertion along the needle axis
/// (positive going deeper).
pub const COMMANDED_VELOCITY_MPS: &str = "commanded_velocity_mps";
/// Tool height along the surface normal, in metres (positive away from the
/// surface).
pub const NORMAL_POSITION_M: &str = "normal_position_m";
/// Tangential force resisting the sliding, in newtons: positive when it
/// opposes the motion (so a dissipative contact gives
/// `friction_force_n * tangential_velocity_mps >= 0`).
pub const FRICTION_FORCE_N: &str = "friction_force_n";
/// Tangential force the device was commanded to apply, in newtons (same
/// axis and sign as `tangential_position_m`).
pub const TANGENTIAL_COMMAND_FORCE_N: &str = "tangential_command_force_n";
/// Tool-mounted accelerometer, x axis, in m/s^2 (sensor frame).
pub const ACCEL_X_MPS2: &str = "accel_x_mps2";
/// Tool-mounted accelerometer, y axis, in m/s^2 (sensor frame).
pub const ACCEL_Y_MPS2: &str = "accel_y_mps2";
/// Tool-mounted accelerometer, z axis, in m/s^2 (sensor frame).
pub const ACCEL_Z_MPS2: &str = "accel_z_mps2";
/// Single-axis vibration sensor on the tool (a one-axis accelerometer or piezo pickup), along
/// the sensor's own axis, in m/s^2. An alternative to the three `accel_*_mps2` axes for rigs
/// that have only one.
///
/// It must be in m/s², not raw ADC counts: the spectrotemporal features keep the vibration's
/// amplitude by default (only their optional unit-sum scaling is gain-invariant), so two
/// sensors in different counts would not be comparable. A logger's counts are converted on
/// import with a scale factor, `vibration_mps2=adc*0.0049` (the sensor's m/s² per count), or
/// a unit and a factor, `vibration_mps2=adc[g]*0.001` for counts of milli-g.
pub const VIBRATION_MPS2: &str = "vibration_mps2";

// --- Insertion columns -----------------------------------------------------

/// Displacement of the needle tip past the undeformed tissue surface, in
/// metres: zero at first contact, positive inside tissue, negative in air.
pub const DEPTH_M: &str = "depth_m";
/// Force resisting the needle along its axis, in newtons: positive when it
/// pushes the needle back out (i.e. resisting insertion).
pub const AXIAL_FORCE_N: &str = "axial_force_n";
/// Measured needle velocity along its axis, in m/s: positive going deeper
/// (the time derivative of `depth_m`).
pub const VELOCITY_MPS: &str = "velocity_mps";

// --- Plausible magnitudes --------------------------------------------------

/// Largest magnitude a capture accepts in any physical column (positions in m, forces in N,
/// velocities in m/s, accelerations in m/s²), in SI units.
///
/// Finite is not enough: one `1e308` from a logger's overflow sentinel survives parsing,
/// then turns every sample a low-pass or an interpolation touches into garbage (and squares
/// to infinity in any fit). 10⁶ SI is far beyond every rig this format is for (a tool
/// travels millimetres to a metre, loads are below a kilonewton, hand-held tools move at a
/// few m/s, and even shock accelerometers saturate near 10⁵ g ≈ 9.8·10⁵ m/s²), so anything
/// larger is a wrong unit or a sentinel. It also keeps arithmetic safe: a square is at most
/// 10¹², and a sum of squares over 10⁷ samples at most 10¹⁹, nowhere near `f64`'s 10³⁰⁸.
pub const MAX_PHYSICAL_MAGNITUDE: f64 = 1e6;

/// Largest magnitude of `time_s`, in seconds (about 317 years).
///
/// Captures count time from the start of the recording, but imported logs keep their
/// first timestamp, and Unix-epoch seconds (1.7·10⁹ in 2024) are a common clock; epoch
/// milliseconds or nanoseconds read as seconds (10¹² and more) are a unit mistake and are
/// caught.
pub const MAX_TIME_MAGNITUDE_S: f64 = 1e10;

/// The largest magnitude a capture accepts in `column` (SI units): [`MAX_TIME_MAGNITUDE_S`]
/// for `time_s`, [`MAX_PHYSICAL_MAGNITUDE`] for every other column. This is the one place
/// the limits are chosen; the reader, the writer, [`Capture::new`](crate::Capture::new) and
/// the import all ask it.
pub fn magnitude_limit(column: &str) -> f64 {
    if column == TIME_S {
        MAX_TIME_MAGNITUDE_S
    } else {
        MAX_PHYSICAL_MAGNITUDE
    }
}

const RUBBING_REQUIRED: &[&str] = &[TIME_S, TANGENTIAL_POSITION_M, NORMAL_FORCE_N];
const RUBBING_OPTIONAL: &[&str] = &[
    TANGENTIAL_VELOCITY_MPS,
    COMMANDED_VELOCITY_MPS,
    NORMAL_POSITION_M,
    FRICTION_FORCE_N,
    TANGENTIAL_COMMAND_FORCE_N,
    ACCEL_X_MPS2,
    ACCEL_Y_MPS2,
    ACCEL_Z_MPS2,
    VIBRATION_MPS2,
];
const INSERTION_REQUIRED: &[&str] = &[TIME_S, DEPTH_M, AXIAL_FORCE_N];
const INSERTION_OPTIONAL: &[&str] = &[VELOCITY_MPS, COMMANDED_VELOCITY_MPS];

impl CaptureKind {
    /// Every kind, in a fixed order (handy for tests and CLI help).
    pub const ALL: [CaptureKind; 2] = [CaptureKind::Rubbing, CaptureKind::Insertion];

    /// The name used in the metadata line (`kind=rubbing`).
    pub fn as_str(self) -> &'static str {
        match self {
            CaptureKind::Rubbing => "rubbing",
            CaptureKind::Insertion => "insertion",
        }
    }

    /// Columns every capture of this kind must have, `time_s` first.
    /// See the `*_M`/`*_N`/... constants in this module for each column's
    /// meaning and sign convention.
    pub fn required_columns(self) -> &'static [&'static str] {
        match self {
            CaptureKind::Rubbing => RUBBING_REQUIRED,
            CaptureKind::Insertion => INSERTION_REQUIRED,
        }
    }

    /// Columns a capture of this kind may additionally have, in the
    /// canonical order (files may list them in any order after `time_s`).
    pub fn optional_columns(self) -> &'static [&'static str] {
        match self {
            CaptureKind::Rubbing => RUBBING_OPTIONAL,
            CaptureKind::Insertion => INSERTION_OPTIONAL,
        }
    }

    /// Whether `name` is a required or optional column of this kind.
    pub fn allows_column(self, name: &str) -> bool {
        self.required_columns().contains(&name) || self.optional_columns().contains(&name)
    }
}

impl fmt::Display for CaptureKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Error returned when parsing an unknown capture kind name.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown capture kind `{0}` (expected `rubbing` or `insertion`)")]
pub struct UnknownKind(pub String);

impl FromStr for CaptureKind {
    type Err = UnknownKind;

    /// Parses the exact lowercase names written by [`CaptureKind::as_str`].
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        CaptureKind::ALL
            .into_iter()
            .find(|k| k.as_str() == s)
            .ok_or_else(|| UnknownKind(s.to_owned()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for kind in CaptureKind::ALL {
            assert_eq!(kind.as_str().parse::<CaptureKind>(), Ok(kind));
            assert_eq!(kind.to_string(), kind.as_str());
        }
        assert_eq!("rubbing".parse::<CaptureKind>(), Ok(CaptureKind::Rubbing));
        assert_eq!(
            "Rubbing".parse::<CaptureKind>(),
            Err(UnknownKind("Rubbing".into()))
        );
        assert_eq!(
            "".parse::<CaptureKind>().unwrap_err().to_string(),
            "unknown capture kind `` (expected `rubbing` or `insertion`)"
        );
    }

    #[test]
    fn column_lists_are_well_formed() {
        for kind in CaptureKind::ALL {
            assert_eq!(kind.required_columns()[0], TIME_S);
            let all: Vec<&str> = kind
                .required_columns()
                .iter()
                .chain(kind.optional_columns())
                .copied()
                .collect();
            for (i, name) in all.iter().enumerate() {
                assert!(!all[..i].contains(name), "{name} listed twice for {kind}");
                assert!(kind.allows_column(name));
                // Every column is unit-suffixed.
                assert!(
                    ["_s", "_m", "_n", "_mps", "_mps2"]
                        .iter()
                        .any(|suffix| name.ends_with(suffix)),
                    "{name} has no unit suffix"
                );
            }
        }
        assert_eq!(
            CaptureKind::Insertion.required_columns(),
            &["time_s", "depth_m", "axial_force_n"]
        );
        assert!(!CaptureKind::Insertion.allows_column("friction_force_n"));
        assert!(!CaptureKind::Rubbing.allows_column("depth_m"));
        assert!(CaptureKind::Rubbing.allows_column(VIBRATION_MPS2));
        assert!(!CaptureKind::Insertion.allows_column(VIBRATION_MPS2));
    }

    #[test]
    fn magnitude_limits() {
        assert_eq!(magnitude_limit(TIME_S), MAX_TIME_MAGNITUDE_S);
        for kind in CaptureKind::ALL {
            for name in kind
                .required_columns()
                .iter()
                .chain(kind.optional_columns())
                .skip(1)
            {
                assert_eq!(magnitude_limit(name), MAX_PHYSICAL_MAGNITUDE, "{name}");
            }
        }
        // Unix-epoch seconds are times; epoch milliseconds are not.
        const { assert!(1.8e9 <= MAX_TIME_MAGNITUDE_S && 1.7e12 > MAX_TIME_MAGNITUDE_S) };
    }
}

//! `--device NAME[:OPTION]`, as `palpus run`, `palpus capture` and `palpus devices` take it:
//! any backend of the device registry.

use haptics::{DeviceChoice, Registry};

/// One device of the registry, with its option.
pub(crate) fn parse_device(s: &str) -> Result<DeviceChoice, String> {
    Registry::builtin().choose(s).map_err(|e| e.to_string())
}

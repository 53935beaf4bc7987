//! Running the `palpus` binary from chain tests.

use std::process::{Command, Output};

/// Runs `palpus ARGS` without a vendor library configured in the environment.
pub fn palpus(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_palpus"))
        .args(args)
        .env_remove("PALPUS_DHD_LIBRARY")
        .output()
        .expect("the palpus binary runs")
}

/// Everything it printed, stdout then stderr.
pub fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

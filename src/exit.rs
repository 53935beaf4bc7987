//! The exit codes palpus returns beyond 0 (done) and 1 (an error before or without a haptic
//! run), so that a script tells a session that ended early, and why, from one that never
//! started:
//!
//! | code | meaning |
//! |---|---|
//! | 3 | the haptic thread stalled and the watchdog released the force |
//! | 4 | the device failed, faulted or was closed under the loop |
//! | 5 | the loop ended early for another reason (its recorder, a panic) |

use std::path::{Path, PathBuf};

use haptics::{EarlyEnd, EndCause};

/// A run of the haptic loop that ended before its end, with where its recording is.
#[derive(Debug, thiserror::Error)]
#[error("{what} ended early: {end}{}", recording_note(.partial))]
pub struct EndedEarly {
    what: String,
    end: EarlyEnd,
    partial: Option<PathBuf>,
}

fn recording_note(partial: &Option<PathBuf>) -> String {
    partial.as_ref().map_or_else(String::new, |p| {
        format!(
            "; what it recorded is in {} (the target was left as it was)",
            p.display()
        )
    })
}

impl EndedEarly {
    /// `what` (a session part, a benchmark) ended with `end`; `partial`: the recording it
    /// left under its partial name, if it left one.
    pub fn new(what: impl Into<String>, end: &EarlyEnd, partial: Option<&Path>) -> Self {
        Self {
            what: what.into(),
            end: end.clone(),
            partial: partial.map(Path::to_owned),
        }
    }

    /// The exit code of this end (see the module's table).
    pub fn exit_code(&self) -> u8 {
        match self.end.cause {
            Some(EndCause::Watchdog) => 3,
            Some(EndCause::Device) => 4,
            None => 5,
        }
    }
}

/// The exit code of a command that failed with `error`.
pub fn exit_code(error: &anyhow::Error) -> u8 {
    error
        .downcast_ref::<EndedEarly>()
        .map_or(1, EndedEarly::exit_code)
}

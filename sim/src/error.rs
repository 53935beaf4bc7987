//! Every failure of the simulated world and its protocols, as one type.

use std::path::PathBuf;

use capture::CaptureError;

/// Why generating captures failed: a protocol's setting out of range, or a capture that could
/// not be built or written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SimError {
    /// A file or folder could not be created or written.
    #[error("cannot {action} {}", path.display())]
    Io {
        /// What was being done (`create`, `write`).
        action: &'static str,
        /// The path that failed.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A generated capture could not be built or written.
    #[error("capture {}", path.display())]
    GeneratedCapture {
        /// The capture's path, relative to the output folder.
        path: PathBuf,
        /// What was wrong.
        #[source]
        source: Box<CaptureError>,
    },
    /// A setting of a simulated protocol is out of its range.
    #[error("{name} = {value}: must be {reason}")]
    Setting {
        /// The setting.
        name: &'static str,
        /// Its value.
        value: f64,
        /// What it must be.
        reason: &'static str,
    },
}

//! Identification of haptic dynamics from captures.
//!
//! This crate is pure computation on data: it knows nothing of threads, devices or rendering.
//! Today it holds the capture format ([`capture`]): the CSV files every recording is stored in,
//! with a strict reader whose errors name the file, line and column.

pub mod baselines;
pub mod capture;
pub mod identification;
pub mod metrics;
pub mod model_file;
pub mod signal;
pub mod svr;

pub use capture::{
    Capture, CaptureError, CaptureErrorKind, CaptureKind, CaptureReader, CaptureWriter, FORMAT_VERSION,
    Metadata, write_atomically,
};

//! The capture reader on any bytes, with each expected kind: it returns, never panics.
#![no_main]

use capture::{Capture, CaptureKind};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let file = std::path::Path::new("fuzz/capture.csv");
    for expected in [None, Some(CaptureKind::Rubbing), Some(CaptureKind::Insertion)] {
        if let Err(e) = Capture::read_from(data, file, expected) {
            assert!(e.to_string().contains("fuzz/capture.csv"), "{e}");
        }
    }
});

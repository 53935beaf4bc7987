//! A recognizer file's text through the one reader `recognize eval` and `run` share.
#![no_main]

use libfuzzer_sys::fuzz_target;
use recognize::RecognizerFile;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let file = std::path::Path::new("fuzz/recognizer.json");
    if let Err(e) = RecognizerFile::from_json(text, file) {
        assert!(e.to_string().contains("fuzz/recognizer.json"), "{e}");
    }
});

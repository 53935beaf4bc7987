//! The two readers of a recognizer file agree: a file `palpus run` can start a live
//! recognizer from is one `recognize eval` can evaluate (what the evaluation reads of the file
//! alone: its features, windows and anytime settings).
#![no_main]

use haptics::LiveRecognizer;
use libfuzzer_sys::fuzz_target;
use recognize::DEFAULT_MEMORY_S;
use recognize::{FeatureNeeds, RecognizerFile};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(model) = RecognizerFile::from_json(text, std::path::Path::new("fuzz/recognizer.json")) else {
        return;
    };
    let rate_hz = model.windowing().map_or(1000.0, |w| w.rate_hz);
    if LiveRecognizer::new(&model, rate_hz).is_err() {
        return;
    }
    if let Err(e) = FeatureNeeds::evaluation(&model, &[]) {
        panic!("run accepts it, eval refuses it: {e}");
    }
    if let Some(params) = model.sequential_params(DEFAULT_MEMORY_S)
        && model.sequential_windowing().is_some()
    {
        assert!(params.build().is_ok(), "run builds its anytime settings, eval's sequential read cannot");
        if let Err(e) = FeatureNeeds::sequential(&model) {
            panic!("run accepts it, eval --sequential refuses it: {e}");
        }
    }
});

//! A model file's bytes through the reader every command uses (parse and validate): an error
//! naming the file, or a model whose every SVR and law is well formed.
#![no_main]

use identify::ModelFile;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let file = std::path::Path::new("fuzz/model.json");
    match ModelFile::from_slice(data, file) {
        Ok(model) => {
            // A model that passed is one a law can evaluate: finite inputs give a number.
            let x: Vec<f64> = model.input_range.iter().map(|r| 0.5 * (r[0] + r[1])).collect();
            let _ = model.predict(&x);
        }
        Err(e) => assert!(e.to_string().contains("fuzz/model.json"), "{e}"),
    }
});

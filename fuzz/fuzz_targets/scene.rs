//! A scene's text through the scene reader: an error naming the file and key, or a scene.
#![no_main]

use libfuzzer_sys::fuzz_target;
use palpus::scene::Scene;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let file = std::path::Path::new("fuzz/scene.toml");
    if let Err(e) = Scene::parse(text, file) {
        assert!(e.to_string().contains("fuzz/scene.toml"), "{e}");
    }
});

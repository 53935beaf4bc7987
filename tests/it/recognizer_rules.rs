//! One rule per recognizer file, whoever reads it: edits of the committed SVM recognizer that
//! `palpus run` started a live recognizer from while `recognize eval` refused them (found by
//! mutating every field of the file and running both readers) are refused on reading, naming
//! the field, so no reader meets them.

use std::path::Path;

use haptics::LiveRecognizer;
use recognize::RecognizerFile;

fn committed_json() -> serde_json::Value {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/models/nakano_svm.json");
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn read(json: &serde_json::Value) -> Result<RecognizerFile, String> {
    RecognizerFile::from_json(&json.to_string(), Path::new("edited.json")).map_err(|e| e.to_string())
}

#[test]
fn edits_one_reader_accepted_and_another_refused_are_refused_on_reading() {
    let json = committed_json();
    let model = read(&json).expect("the committed recognizer");
    assert!(LiveRecognizer::new(&model, 1000.0).is_ok());

    type Edit = fn(&mut serde_json::Value);
    let cases: [(&str, Edit, &str); 4] = [
        (
            // The live recognizer read every window as unreadable; eval refused it.
            "one pair's sigmoid removed",
            |j| {
                j["body"]["svc"]["machines"][0]
                    .as_object_mut()
                    .unwrap()
                    .remove("sigmoid");
            },
            "`body.svc.machines`: pair (0, 1): no sigmoid where params.probability is true",
        ),
        (
            "fitted without probabilities",
            |j| {
                j["body"]["svc"]["params"]["probability"] = false.into();
                for m in j["body"]["svc"]["machines"].as_array_mut().unwrap() {
                    m.as_object_mut().unwrap().remove("sigmoid");
                }
            },
            "`body.svc.params.probability`: false: an SVM over windows decides by class probabilities",
        ),
        (
            // A 25-sample window under a 675-sample margin: a stroke's first windows could not
            // be mirrored; live skipped them, eval --sequential stopped at the first.
            "a window too short for its edge's mirror",
            |j| j["body"]["windowing"]["window_samples"] = 25.into(),
            "`body.windowing.window_samples`: 25 is not long enough to be decided at its last sample",
        ),
        (
            "an empty class name",
            |j| j["classes"][0] = "".into(),
            "`classes[0]`: an empty name",
        ),
    ];
    for (what, edit, message) in cases {
        let mut edited = json.clone();
        edit(&mut edited);
        let err = read(&edited).expect_err(what);
        assert!(
            err.contains("edited.json") && err.contains(message),
            "{what}: {err}"
        );
    }
    // The boundary of the mirror rule: the shortest window the margin allows is read, and a
    // live recognizer starts from it.
    let margin: u64 = 675;
    let shortest = margin.div_ceil(7) + 1;
    let mut edited = json.clone();
    edited["body"]["windowing"]["window_samples"] = shortest.into();
    let model = read(&edited).expect("shortest window");
    assert!(LiveRecognizer::new(&model, 1000.0).is_ok());
    edited["body"]["windowing"]["window_samples"] = (shortest - 1).into();
    assert!(read(&edited).is_err());
}

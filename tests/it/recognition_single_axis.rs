//! A recognizer trained on single-axis vibration captures (`vibration_mps2`) recognizes
//! generated scratches: the simulated Sinapov captures with only one accelerometer axis kept,
//! as a rig with a one-axis sensor would record them.

use std::path::Path;

use capture::Capture;
use capture::kind::{ACCEL_X_MPS2, ACCEL_Y_MPS2, ACCEL_Z_MPS2, VIBRATION_MPS2};
use recognize::{LabelledCapture, Method, TrainSettings, train};
use sim::sinapov::scratch_capture;
use sim::{Behaviour, household_surfaces};

const SEED: u64 = 1;
/// Surfaces of the generated set used here (of 21): enough classes for the check to mean
/// something, few enough for a two-core machine.
const SURFACES: usize = 6;

/// `capture` with its accelerometer replaced by `axis` alone, as `vibration_mps2`.
fn keep_axis(capture: &Capture, axis: &str) -> Capture {
    let accel = [ACCEL_X_MPS2, ACCEL_Y_MPS2, ACCEL_Z_MPS2];
    let mut names = Vec::new();
    let mut columns = Vec::new();
    for name in capture.columns() {
        if name == axis {
            names.push(VIBRATION_MPS2.to_owned());
        } else if accel.contains(&name.as_str()) {
            continue;
        } else {
            names.push(name.clone());
        }
        columns.push(capture.column(name).expect("listed column").to_vec());
    }
    Capture::new(capture.metadata().clone(), names, columns).expect("valid single-axis capture")
}

/// The generated scratches of one behaviour, trials `trials`, each reduced by `reduce`.
fn captures(trials: std::ops::Range<u32>, reduce: impl Fn(Capture) -> Capture) -> Vec<LabelledCapture> {
    let surfaces = household_surfaces();
    surfaces[..SURFACES]
        .iter()
        .flat_map(|s| trials.clone().map(move |t| (s, t)))
        .map(|(s, t)| {
            let capture = reduce(scratch_capture(s, Behaviour::ALL[0], t, SEED).expect("capture"));
            let path = format!("{}_{t}.csv", s.name);
            LabelledCapture::new(capture, Path::new(&path), "00".into()).expect("labelled")
        })
        .collect()
}

fn accuracy(reduce: impl Fn(Capture) -> Capture + Copy) -> f64 {
    let model = train(&captures(0..7, reduce), &TrainSettings::new(Method::Knn)).expect("train");
    let eval = model.evaluate(&captures(7..10, reduce), None).expect("evaluate");
    eval.confusion.accuracy().expect("decisions")
}

/// Six surfaces, one behaviour, trained on trials 0–6 and tested on 7–9: chance is 1/6, and the
/// three axes recognize every test scratch. One axis hears less of the vibration (the others'
/// share of the magnitude is gone), so a few scratches may go wrong, not most.
#[test]
fn single_axis_captures_train_and_recognize_generated_scratches() {
    let three = accuracy(|c| c);
    for axis in [ACCEL_X_MPS2, ACCEL_Y_MPS2, ACCEL_Z_MPS2] {
        let one = accuracy(|c| {
            let single = keep_axis(&c, axis);
            assert!(single.has_column(VIBRATION_MPS2) && !single.has_column(axis));
            single
        });
        eprintln!("{axis} alone: accuracy {one} (three axes {three})");
        assert!(one >= 0.8, "{axis} alone: accuracy {one}");
    }
}

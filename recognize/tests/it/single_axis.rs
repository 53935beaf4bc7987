//! Recognition from a single-axis vibration sensor (`vibration_mps2`): spectral features train
//! and decide on captures that have no three-axis accelerometer.

use std::path::Path;

use capture::kind::{NORMAL_FORCE_N, TANGENTIAL_POSITION_M, TIME_S, VIBRATION_MPS2};
use capture::{Capture, CaptureKind, Metadata};
use recognize::InputError;
use recognize::{
    BEHAVIOUR_KEY, FeatureSet, LABEL_KEY, LabelledCapture, Method, RecognizeError, TRIAL_KEY, TrainSettings,
    train,
};

const RATE_HZ: f64 = 400.0;

/// A 3 s scratch of `surface`: gravity on the sensor's axis, the surface's two tones, and
/// deterministic noise that differs per trial.
fn scratch(surface: &str, tones_hz: [f64; 2], trial: u32) -> LabelledCapture {
    let n = 1200;
    let mut rng = capture::rng::SplitMix64::new(
        0x9e37_79b9_7f4a_7c15_u64 ^ (u64::from(trial) << 17) ^ tones_hz[0].to_bits(),
    );
    let mut noise = move || rng.next_f64() - 0.5;
    let phase = f64::from(trial) * 0.7;
    let vibration: Vec<f64> = (0..n)
        .map(|i| {
            let t = i as f64 / RATE_HZ;
            let tone = |f: f64| (std::f64::consts::TAU * f * t + phase).sin();
            9.81 + 0.5 * tone(tones_hz[0]) + 0.3 * tone(tones_hz[1]) + 0.2 * noise()
        })
        .collect();
    let meta = Metadata::new(CaptureKind::Rubbing, "test", RATE_HZ)
        .with(LABEL_KEY, surface)
        .with(BEHAVIOUR_KEY, "scratch")
        .with(TRIAL_KEY, trial);
    let columns = [TIME_S, TANGENTIAL_POSITION_M, NORMAL_FORCE_N, VIBRATION_MPS2]
        .map(String::from)
        .to_vec();
    let time = (0..n).map(|i| i as f64 / RATE_HZ).collect();
    let capture = Capture::new(meta, columns, vec![time, vec![0.0; n], vec![1.0; n], vibration])
        .expect("valid capture");
    let path = format!("{surface}_{trial}.csv");
    LabelledCapture::new(capture, Path::new(&path), "00".into()).expect("labelled")
}

fn surfaces(trials: std::ops::Range<u32>) -> Vec<LabelledCapture> {
    let kinds = [
        ("wood", [35.0, 90.0]),
        ("metal", [140.0, 170.0]),
        ("cloth", [60.0, 110.0]),
    ];
    kinds
        .iter()
        .flat_map(|&(name, tones)| trials.clone().map(move |t| scratch(name, tones, t)))
        .collect()
}

#[test]
fn a_recognizer_trained_on_single_axis_captures_recognizes_them() {
    let train_set = surfaces(0..5);
    for method in [Method::Knn, Method::Svm] {
        let model = train(&train_set, &TrainSettings::new(method)).expect("train");
        assert_eq!(model.feature_set(), FeatureSet::Spectral);
        let eval = model.evaluate(&surfaces(5..8), None).expect("evaluate");
        assert_eq!(eval.confusion.accuracy(), Some(1.0), "{}", method.name());
    }
}

#[test]
fn missing_columns_name_both_accelerometer_options() {
    let mut bare = scratch("wood", [35.0, 90.0], 0);
    let capture = bare.capture.clone();
    let keep: Vec<String> = capture
        .columns()
        .iter()
        .filter(|c| *c != VIBRATION_MPS2)
        .cloned()
        .collect();
    let columns = keep
        .iter()
        .map(|c| capture.column(c).expect("present").to_vec())
        .collect();
    bare.capture = Capture::new(capture.metadata().clone(), keep, columns).expect("valid");
    let err = FeatureSet::Spectral
        .check_columns(std::slice::from_ref(&bare))
        .expect_err("no vibration");
    assert_eq!(
        err.to_string(),
        "wood_0.csv: `--features spectral` needs the columns accel_x_mps2, accel_y_mps2, \
         accel_z_mps2 (or, instead of the three axes, vibration_mps2), which this capture lacks"
    );
    // `both` takes each window's histogram from the single axis too (this scratch lacks only
    // the columns of Nakano's features).
    let single = scratch("wood", [35.0, 90.0], 0);
    assert!(FeatureSet::Spectral.missing_columns(&single).is_empty());
    let missing = FeatureSet::Both.missing_columns(&single);
    assert!(missing.iter().all(|m| !m.contains("accel")), "{missing:?}");
    let err = FeatureSet::Both.check_columns(&[bare]).expect_err("no vibration");
    assert!(
        matches!(&err, RecognizeError::Input(InputError::MissingColumns { missing, .. })
            if missing.last().is_some_and(|m| m.ends_with("(or, instead of the three axes, vibration_mps2)"))),
        "{err}"
    );
}

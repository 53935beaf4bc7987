//! `--features both` on a rubbing capture whose vibration comes from a single-axis sensor
//! (`vibration_mps2`): each window's histogram is of that axis, exactly as it is of the three
//! axes' magnitude when the sensor is three-axis.

use std::path::Path;

use capture::kind::{
    ACCEL_X_MPS2, ACCEL_Y_MPS2, ACCEL_Z_MPS2, FRICTION_FORCE_N, NORMAL_FORCE_N, NORMAL_POSITION_M,
    TANGENTIAL_POSITION_M, TIME_S, VIBRATION_MPS2,
};
use capture::{Capture, CaptureKind, Metadata};
use recognize::{FeatureSet, LABEL_KEY, LabelledCapture, Method, SvmC, TRIAL_KEY, TrainSettings, train};

const RATE_HZ: f64 = 1000.0;
const SAMPLES: usize = 4500;

/// A 4.5 s rub of `surface` at 5 mm/s whose roughness and friction are the same on every
/// surface (up to noise), so that only the vibration's tones tell surfaces apart. The vibration
/// (gravity plus the tones, always positive) is one `vibration_mps2` column, or, with
/// `three_axes`, the z axis of an accelerometer whose x and y read 0: their magnitude is the
/// same signal.
fn rub(surface: &str, tones_hz: [f64; 2], trial: u32, three_axes: bool) -> LabelledCapture {
    let mut rng = capture::rng::SplitMix64::new(
        0x2545_f491_4f6c_dd1d_u64 ^ (u64::from(trial) << 21) ^ tones_hz[0].to_bits(),
    );
    let mut noise = move || rng.next_f64() - 0.5;
    let t: Vec<f64> = (0..SAMPLES).map(|i| i as f64 / RATE_HZ).collect();
    let phase = f64::from(trial) * 0.9;
    let position: Vec<f64> = t.iter().map(|t| 0.005 * t).collect();
    let height: Vec<f64> = position
        .iter()
        .map(|x| 1e-5 * (std::f64::consts::TAU * x / 0.002).sin() + 1e-6 * noise())
        .collect();
    let friction: Vec<f64> = (0..SAMPLES).map(|_| 0.12 + 0.01 * noise()).collect();
    let vibration: Vec<f64> = t
        .iter()
        .map(|t| {
            let tone = |f: f64| (std::f64::consts::TAU * f * t + phase).sin();
            9.81 + 0.8 * tone(tones_hz[0]) + 0.5 * tone(tones_hz[1]) + 0.3 * noise()
        })
        .collect();
    let meta = Metadata::new(CaptureKind::Rubbing, "test", RATE_HZ)
        .with(LABEL_KEY, surface)
        .with(TRIAL_KEY, trial);
    let mut columns = vec![
        TIME_S,
        TANGENTIAL_POSITION_M,
        NORMAL_FORCE_N,
        NORMAL_POSITION_M,
        FRICTION_FORCE_N,
    ];
    let mut data = vec![t, position, vec![0.3; SAMPLES], height, friction];
    if three_axes {
        columns.extend([ACCEL_X_MPS2, ACCEL_Y_MPS2, ACCEL_Z_MPS2]);
        data.extend([vec![0.0; SAMPLES], vec![0.0; SAMPLES], vibration]);
    } else {
        columns.push(VIBRATION_MPS2);
        data.push(vibration);
    }
    let columns = columns.into_iter().map(String::from).collect();
    let capture = Capture::new(meta, columns, data).expect("valid capture");
    let path = format!("{surface}_{trial}.csv");
    LabelledCapture::new(capture, Path::new(&path), "00".into()).expect("labelled")
}

fn surfaces(trials: std::ops::Range<u32>, three_axes: bool) -> Vec<LabelledCapture> {
    let tones = [
        ("wood", [35.0, 90.0]),
        ("metal", [140.0, 170.0]),
        ("cloth", [60.0, 110.0]),
    ];
    tones
        .iter()
        .flat_map(|&(name, tones)| trials.clone().map(move |t| rub(name, tones, t, three_axes)))
        .collect()
}

fn both(method: Method) -> TrainSettings {
    TrainSettings {
        features: FeatureSet::Both,
        // A window's histogram needs five 0.64 s frames at half a frame's hop (1.92 s).
        window_s: 2.0,
        train_window_s: Some(2.0),
        hop_s: 0.25,
        c: SvmC::Fixed(10.0),
        ..TrainSettings::new(method)
    }
}

#[test]
fn both_features_accept_a_single_axis_and_match_three_axes_of_the_same_vibration() {
    let (one, three) = (surfaces(0..2, false), surfaces(0..2, true));
    assert!(one.iter().all(|c| FeatureSet::Both.missing_columns(c).is_empty()));
    for method in [Method::Som, Method::Knn, Method::Svm] {
        let single = train(&one, &both(method)).expect("trains on one axis");
        let reference = train(&three, &both(method)).expect("trains on three axes");
        assert_eq!(single.feature_set(), FeatureSet::Both, "{}", method.name());
        assert_eq!(single.body, reference.body, "{}", method.name());
    }
}

#[test]
fn both_features_from_a_single_axis_recognize_surfaces_that_differ_only_in_vibration() {
    let model = train(&surfaces(0..2, false), &both(Method::Knn)).expect("train");
    let eval = model.evaluate(&surfaces(2..4, false), None).expect("evaluate");
    let accuracy = eval.confusion.accuracy().expect("decisions");
    assert!(
        accuracy >= 0.95,
        "accuracy {accuracy}\n{}",
        eval.confusion.to_text()
    );
    // The histogram part decides: Nakano's five features alone cannot tell these apart.
    let nakano = TrainSettings {
        features: FeatureSet::Nakano,
        ..both(Method::Knn)
    };
    let model = train(&surfaces(0..2, false), &nakano).expect("train");
    let eval = model.evaluate(&surfaces(2..4, false), None).expect("evaluate");
    let chance_like = eval.confusion.accuracy().expect("decisions");
    assert!(chance_like < 0.7, "nakano alone {chance_like}");
}

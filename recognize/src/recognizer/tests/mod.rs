//! The recognizer's tests, by what they check, over the rubbing captures and recognizers built
//! here.

use std::path::Path;

use super::*;
use crate::RecognizeError;
use crate::features::histogram_names;
use crate::features::spectral::Histogram;
use crate::features::{FeatureSet, NakanoWindowing, window_vectors};
use crate::knn::KnnParams;
use crate::recognizer::labelled::class_list;
use crate::recognizer::sequential_eval::{Stroke, StrokeWindow};
use crate::recognizer::train::training_windows;
use crate::som::SomParams;
use crate::svc::{CSearch, Svc, SvcParams};
use crate::{DataError, InputError, SettingError, UsageError};
use capture::kind::{FRICTION_FORCE_N, NORMAL_FORCE_N, NORMAL_POSITION_M, TANGENTIAL_POSITION_M, TIME_S};
use capture::{Capture, CaptureKind, Metadata};

mod evaluation;
mod files;
mod fusion;
mod training;

/// A rubbing capture of a sine roughness of `amplitude_m` and `wavelength_m` with friction
/// `friction_n`, 5 mm/s at 1 kHz for `seconds`.
fn rubbing(
    surface: &str,
    amplitude_m: f64,
    wavelength_m: f64,
    friction_n: f64,
    seconds: f64,
) -> LabelledCapture {
    rubbing_at(surface, amplitude_m, wavelength_m, friction_n, seconds, 5e-3)
}

/// [`rubbing`] at `speed_m_s` (0: a tip that never slides).
fn rubbing_at(
    surface: &str,
    amplitude_m: f64,
    wavelength_m: f64,
    friction_n: f64,
    seconds: f64,
    speed_m_s: f64,
) -> LabelledCapture {
    let n = (seconds * 1000.0) as usize;
    let t: Vec<f64> = (0..n).map(|k| k as f64 * 1e-3).collect();
    let x: Vec<f64> = t.iter().map(|t| speed_m_s * t).collect();
    let z: Vec<f64> = x
        .iter()
        .map(|x| amplitude_m * (x * std::f64::consts::TAU / wavelength_m).sin())
        .collect();
    let f: Vec<f64> = (0..n)
        .map(|k| friction_n * (1.0 + 0.05 * ((k * 7919) % 13) as f64 / 13.0))
        .collect();
    let meta = Metadata::new(CaptureKind::Rubbing, "test", 1000.0).with(LABEL_KEY, surface);
    let columns = [
        TIME_S,
        TANGENTIAL_POSITION_M,
        NORMAL_POSITION_M,
        NORMAL_FORCE_N,
        FRICTION_FORCE_N,
    ]
    .map(String::from)
    .to_vec();
    let capture = Capture::new(meta, columns, vec![t, x, z, vec![0.3; n], f]).expect("valid capture");
    LabelledCapture::new(capture, Path::new(surface), "00".into()).expect("labelled")
}

fn three_surfaces(seconds: f64) -> Vec<LabelledCapture> {
    vec![
        rubbing("fine", 5e-6, 0.3e-3, 0.10, seconds),
        rubbing("coarse", 30e-6, 1.5e-3, 0.20, seconds),
        rubbing("smooth", 1e-6, 0.8e-3, 0.05, seconds),
    ]
}

/// One classifier per behaviour, `poke` then `rub`: `make` gets the behaviour and whether it
/// carries a reliability weight (only `poke` does).
fn poke_and_rub<T>(make: impl Fn(Option<String>, bool) -> T) -> Vec<T> {
    ["poke", "rub"]
        .map(|b| make(Some(b.to_owned()), b == "poke"))
        .into()
}

/// A k-NN and an SVM recognizer over two behaviours of three classes, built without
/// captures: `poke` has a reliability weight, `rub` (as in a file written before weights
/// were stored, or with too few trials) has none.
fn sinapov_recognizers() -> [RecognizerFile; 2] {
    use crate::svc::CvPoint;
    let x: Vec<Vec<f64>> = (0..6)
        .map(|i| {
            (0..crate::features::spectral::FEATURE_LEN)
                .map(|j| (i / 2) as f64 + 0.01 * ((i * 31 + j * 7) % 11) as f64)
                .collect()
        })
        .collect();
    let y = [0, 0, 1, 1, 2, 2];
    let knn = KnnParams::default().fit(&x, &y, 3).expect("k-NN");
    let params = SvcParams {
        c: 10.0,
        probability: false,
        ..SvcParams::default()
    };
    let svc = Svc::fit(params, &x, &y, 3).expect("SVC");
    let classes: Vec<String> = ["a", "b", "c"].map(String::from).to_vec();
    let knn_body = RecognizerBody::Knn {
        histogram: Histogram::default(),
        behaviours: poke_and_rub(|behaviour, weighted| BehaviourKnn {
            behaviour,
            knn: knn.clone(),
            reliability: weighted.then_some(0.8),
            reliability_folds: weighted.then_some(5),
        }),
    };
    let search = CSearch {
        folds: 5,
        grid: vec![
            CvPoint {
                c: 1.0,
                accuracy: 0.5,
            },
            CvPoint {
                c: 10.0,
                accuracy: 0.8,
            },
        ],
        chosen_c: 10.0,
        separable_from: None,
        vector_weight: None,
    };
    let svm_body = RecognizerBody::Svm {
        histogram: Histogram::default(),
        behaviours: poke_and_rub(|behaviour, weighted| BehaviourSvc {
            behaviour,
            svc: svc.clone(),
            reliability: weighted.then_some(0.8),
            c_search: weighted.then(|| search.clone()),
        }),
    };
    [knn_body, svm_body]
        .map(|body| RecognizerFile::assemble(classes.clone(), histogram_names(), body, &[], 6))
}

/// `c`, read from `path` instead.
fn from(mut c: LabelledCapture, path: &str) -> LabelledCapture {
    c.reference.path = path.into();
    c
}

/// Rubbing captures of `n` surfaces, `surface_00`…, each a different roughness and friction.
fn many_surfaces(n: usize, seconds: f64) -> Vec<LabelledCapture> {
    (0..n)
        .map(|i| {
            let i_f = i as f64;
            rubbing(
                &format!("surface_{i:02}"),
                2e-6 * (1.0 + i_f),
                0.3e-3 + 0.1e-3 * (i_f % 5.0),
                0.05 + 0.02 * i_f,
                seconds,
            )
        })
        .collect()
}

/// `c` with a single-axis vibration: gravity and a tone whose frequency tells the surface.
fn with_vibration(c: LabelledCapture, tone_hz: f64) -> LabelledCapture {
    let capture = &c.capture;
    let mut columns = capture.columns().to_vec();
    let mut data = capture.data().to_vec();
    let vibration = capture
        .time()
        .iter()
        .enumerate()
        .map(|(k, t)| {
            9.81 + 0.5 * (std::f64::consts::TAU * tone_hz * t).sin() + 0.05 * ((k * 7919) % 17) as f64 / 17.0
        })
        .collect();
    columns.push(capture::kind::VIBRATION_MPS2.to_owned());
    data.push(vibration);
    let meta = capture.metadata().clone();
    LabelledCapture {
        capture: Capture::new(meta, columns, data).expect("valid"),
        ..c
    }
}

/// Three surfaces with vibration, two trials each, `seconds` long.
pub(super) fn vibrating_surfaces(seconds: f64, trials: std::ops::Range<u32>) -> Vec<LabelledCapture> {
    let mut out = Vec::new();
    for t in trials {
        for (c, tone) in three_surfaces(seconds).into_iter().zip([40.0, 95.0, 150.0]) {
            let mut c = with_vibration(c, tone + f64::from(t));
            let meta = c.capture.metadata().clone().with(TRIAL_KEY, t);
            c.capture =
                Capture::new(meta, c.capture.columns().to_vec(), c.capture.data().to_vec()).expect("valid");
            c.reference.path = format!("{}_{t}.csv", c.label).into();
            out.push(c);
        }
    }
    out
}

/// [`three_surfaces`] as trials `trials`, each with a vibration tone: `fine` and `coarse` share
/// theirs (60 Hz), so the vibration cannot tell them apart; the friction can.
pub(super) fn with_tones(trials: std::ops::Range<u32>, seconds: f64) -> Vec<LabelledCapture> {
    trials
        .flat_map(|t| {
            three_surfaces(seconds)
                .into_iter()
                .zip([60.0, 60.0, 150.0])
                .map(move |(c, tone)| {
                    let mut c = with_vibration(c, tone);
                    let meta = c.capture.metadata().clone().with(TRIAL_KEY, t);
                    c.capture = Capture::new(meta, c.capture.columns().to_vec(), c.capture.data().to_vec())
                        .expect("valid");
                    c.reference.path = format!("{}_{t}.csv", c.label).into();
                    c
                })
        })
        .collect()
}

/// `method` over `features` in 0.25 s windows every 0.1 s, trained on windows of that length.
pub(super) fn short_windows(method: Method, features: FeatureSet) -> TrainSettings {
    TrainSettings {
        features,
        window_s: 0.25,
        train_window_s: Some(0.25),
        hop_s: 0.1,
        ..TrainSettings::new(method)
    }
}

//! `palpus identify --predictions --plot`: the fit shown against every row of the data.

#![allow(clippy::unwrap_used)] // A failed unwrap is a failed test.

use std::path::{Path, PathBuf};

use crate::common::{fails, json};

use capture::{Capture, CaptureKind, kind};
use identify::{Metrics, ModelFile};

/// The committed Li & Bi capture set.
fn li_bi_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/captures/li_bi")
}

/// One row of a predictions file.
struct Row {
    set: String,
    values: Vec<f64>,
}

/// The header and rows of a predictions file.
fn read_predictions(path: &Path) -> (Vec<String>, Vec<Row>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_owned)
        .collect::<Vec<_>>();
    let rows = lines
        .map(|line| {
            let mut fields = line.split(',');
            let set = fields.next().unwrap().to_owned();
            let values = fields.map(|f| f.parse::<f64>().unwrap()).collect::<Vec<_>>();
            assert_eq!(values.len() + 1, header.len(), "{line}");
            Row { set, values }
        })
        .collect();
    (header, rows)
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1e-12)
}

/// The rows of `capture` a model of `model_kind` describes: in tissue for the needle, all
/// others.
fn described_rows(capture: &Capture, needle: bool) -> Vec<usize> {
    if needle {
        let depth = capture.column(kind::DEPTH_M).unwrap();
        (0..capture.len()).filter(|&i| depth[i] > 0.0).collect()
    } else {
        (0..capture.len()).collect()
    }
}

/// Runs identify with --predictions, --plot and --out on `train` (and `test`), and checks the
/// predictions file against the captures and the model file, and the image.
fn check(model_arg: &str, train: &Path, test: Option<&Path>, inputs: &[&str], output: &str) {
    let dir = tempfile::tempdir().unwrap();
    let (csv, png, model_path) = (
        dir.path().join("p.csv"),
        dir.path().join("p.png"),
        dir.path().join("m.json"),
    );
    let mut args = vec![
        "identify",
        train.to_str().unwrap(),
        "--model",
        model_arg,
        "--out",
        model_path.to_str().unwrap(),
        "--predictions",
        csv.to_str().unwrap(),
        "--plot",
        png.to_str().unwrap(),
        "--plot-size",
        "640x480",
        "--json",
    ];
    if let Some(t) = test {
        args.extend(["--test", t.to_str().unwrap()]);
    }
    json(&args);
    let model = ModelFile::load(&model_path).unwrap();
    let needle = model_arg == "needle";

    let (header, rows) = read_predictions(&csv);
    let mut expected_header = vec!["set".to_owned()];
    expected_header.extend(inputs.iter().map(|s| (*s).to_owned()));
    expected_header.extend([
        output.to_owned(),
        format!("predicted_{output}"),
        "residual_n".to_owned(),
    ]);
    assert_eq!(header, expected_header);
    let names: Vec<&str> = model.inputs.iter().map(|q| q.name.as_str()).collect();
    assert_eq!(names, inputs);

    let capture_kind = if needle {
        CaptureKind::Insertion
    } else {
        CaptureKind::Rubbing
    };
    let n_in = inputs.len();
    let sets: Vec<(&str, &Path, Option<&Metrics>)> = [
        Some(("train", train, model.train_metrics.as_ref())),
        test.map(|t| ("test", t, model.test_metrics.as_ref())),
    ]
    .into_iter()
    .flatten()
    .collect();
    let mut seen = 0;
    for (label, path, metrics) in sets {
        let capture = Capture::read_file(path, capture_kind).unwrap();
        let described = described_rows(&capture, needle);
        let mine: Vec<&Row> = rows.iter().filter(|r| r.set == label).collect();
        // Every row the model describes, not only the thinned rows it was fitted on.
        assert_eq!(mine.len(), described.len(), "{label} rows");
        seen += mine.len();
        let measured = capture.column(output).unwrap();
        let mut squared = 0.0;
        for (row, &i) in mine.iter().zip(&described) {
            let v = &row.values;
            let (x, y, predicted, residual) = (&v[..n_in], v[n_in], v[n_in + 1], v[n_in + 2]);
            assert_eq!(y, measured[i], "{label} row {i}: measured force");
            for (name, &xv) in inputs.iter().zip(x) {
                if capture.has_column(name) {
                    assert_eq!(xv, capture.column(name).unwrap()[i], "{label} row {i}: {name}");
                }
            }
            assert!(predicted.is_finite(), "{label} row {i}: {predicted}");
            let again = model.predict(x);
            assert!(close(predicted, again), "{label} row {i}: {predicted} vs {again}");
            assert!(
                close(residual, y - predicted),
                "{label} row {i}: residual {residual}"
            );
            squared += residual * residual;
        }
        // The rows and inputs are the ones identify evaluated the model on: its RMSE there.
        let rmse = (squared / mine.len() as f64).sqrt();
        let reported = metrics.unwrap().rmse;
        assert!(
            (rmse - reported).abs() <= 1e-9 * reported,
            "{label}: RMSE {rmse} vs {reported}"
        );
    }
    assert_eq!(seen, rows.len(), "rows of no set");

    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&png).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height), (640, 480));
    let pixels = &buf[..info.buffer_size()];
    let step = info.color_type.samples();
    let first = &pixels[..step];
    assert!(
        pixels.chunks_exact(step).any(|p| p != first),
        "{model_arg}: the plot is one colour"
    );
}

#[test]
fn hard_contact_predictions_cover_train_and_test() {
    let root = li_bi_dir();
    check(
        "hard",
        &root.join("hard_contact_train.csv"),
        Some(&root.join("hard_contact_test.csv")),
        &[kind::NORMAL_FORCE_N],
        kind::FRICTION_FORCE_N,
    );
}

#[test]
fn soft_contact_predictions_cover_train_and_test() {
    let root = li_bi_dir();
    check(
        "soft",
        &root.join("soft_contact_train.csv"),
        Some(&root.join("soft_contact_test.csv")),
        &[kind::TANGENTIAL_VELOCITY_MPS, kind::NORMAL_FORCE_N],
        kind::FRICTION_FORCE_N,
    );
}

#[test]
fn needle_predictions_cover_every_in_tissue_row() {
    let root = li_bi_dir();
    // 8148 rows in the training capture, of which the model fits 350: the predictions hold
    // every in-tissue row of both captures.
    check(
        "needle",
        &root.join("needle_train.csv"),
        Some(&root.join("needle_test.csv")),
        &[kind::DEPTH_M, kind::VELOCITY_MPS],
        kind::AXIAL_FORCE_N,
    );
}

#[test]
fn without_a_velocity_column_the_predictions_use_the_velocity_identify_derived() {
    // The soft contact's model reads the sliding speed; a capture without the column makes
    // identify differentiate the position, and the predictions must do the same (the RMSE
    // check in `check` fails otherwise).
    let dir = tempfile::tempdir().unwrap();
    let source = std::fs::read_to_string(li_bi_dir().join("soft_contact_train.csv")).unwrap();
    let mut column = None;
    let stripped: String = source
        .lines()
        .map(|line| {
            if line.starts_with('#') {
                return format!("{line}\n");
            }
            let fields: Vec<&str> = line.split(',').collect();
            let k = *column.get_or_insert_with(|| {
                fields
                    .iter()
                    .position(|f| *f == kind::TANGENTIAL_VELOCITY_MPS)
                    .unwrap()
            });
            let kept: Vec<&str> = fields
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != k)
                .map(|(_, f)| *f)
                .collect();
            format!("{}\n", kept.join(","))
        })
        .collect();
    let train = dir.path().join("soft_no_velocity.csv");
    std::fs::write(&train, stripped).unwrap();
    check(
        "soft",
        &train,
        None,
        &[kind::TANGENTIAL_VELOCITY_MPS, kind::NORMAL_FORCE_N],
        kind::FRICTION_FORCE_N,
    );
}

#[test]
fn a_bad_plot_size_is_refused() {
    let root = li_bi_dir();
    let out = fails(&[
        "identify",
        root.join("hard_contact_train.csv").to_str().unwrap(),
        "--model",
        "hard",
        "--plot",
        "x.png",
        "--plot-size",
        "10x10000",
    ]);
    assert!(out.contains("16–8192"), "{out}");
}

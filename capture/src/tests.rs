//! Whole-capture tests: round trips, in-memory validation, files on disk.

use super::*;
use proptest::prelude::*;

const EXAMPLE: &str = "\
# palpus-capture format=1 kind=rubbing device=sim-omega7 rate_hz=1000 units=si seed=42 surface=sandpaper_120 truth.mu=0.58
time_s,tangential_position_m,normal_position_m,normal_force_n,friction_force_n
0.0,0.0,0.00012,0.3,0.174
0.001,5e-6,0.00013,0.301,0.1738
";

fn strings(names: &[&str]) -> Vec<String> {
    names.iter().map(|&n| n.to_owned()).collect()
}

fn insertion(data: Vec<Vec<f64>>) -> Result<Capture, CaptureError> {
    Capture::new(
        Metadata::new(CaptureKind::Insertion, "sim-needle", 500.0),
        strings(&["time_s", "depth_m", "axial_force_n"]),
        data,
    )
}

fn bytes_of(capture: &Capture) -> Vec<u8> {
    capture.write_to(Vec::new()).unwrap()
}

#[test]
fn documented_example_reads_and_rewrites_byte_for_byte() {
    let capture = Capture::read_from(EXAMPLE.as_bytes(), "example.csv", None).unwrap();
    let meta = capture.metadata();
    assert_eq!(meta.kind(), CaptureKind::Rubbing);
    assert_eq!(meta.device(), "sim-omega7");
    assert_eq!(meta.rate_hz(), 1000.0);
    assert_eq!(meta.get("seed"), Some("42"));
    assert_eq!(meta.get("truth.mu"), Some("0.58"));
    assert_eq!(capture.len(), 2);
    assert!(!capture.is_empty());
    assert_eq!(capture.time(), [0.0, 0.001]);
    assert_eq!(capture.column("tangential_position_m").unwrap(), [0.0, 5e-6]);
    assert_eq!(capture.column("friction_force_n").unwrap(), [0.174, 0.1738]);
    assert!(capture.has_column("normal_position_m"));
    assert!(!capture.has_column("accel_x_mps2"));
    assert_eq!(capture.source(), Path::new("example.csv"));
    assert_eq!(String::from_utf8(bytes_of(&capture)).unwrap(), EXAMPLE);
}

#[test]
fn missing_column_names_the_file() {
    let capture = Capture::read_from(EXAMPLE.as_bytes(), "captures/a.csv", None).unwrap();
    let e = capture.column("accel_x_mps2").unwrap_err();
    assert!(matches!(&e.kind, CaptureErrorKind::MissingColumn(c) if c == "accel_x_mps2"));
    assert_eq!(e.file.as_deref(), Some(Path::new("captures/a.csv")));
    assert_eq!((e.line, e.column.as_deref()), (None, None));
    assert_eq!(e.to_string(), "captures/a.csv: missing column `accel_x_mps2`");

    let e = insertion(vec![vec![0.0], vec![0.0], vec![0.0]])
        .unwrap()
        .column("velocity_mps")
        .unwrap_err();
    assert_eq!(e.to_string(), "<memory>: missing column `velocity_mps`");
}

#[test]
fn new_validates_like_the_writer() {
    let ok = insertion(vec![vec![0.0, 0.1], vec![-1e-3, 2e-3], vec![0.0, 0.5]]).unwrap();
    assert_eq!(ok.len(), 2);
    assert_eq!(ok.source(), Path::new("<memory>"));

    let e = insertion(vec![vec![0.0, 0.1], vec![0.0, 0.0]]).unwrap_err();
    assert!(matches!(
        e.kind,
        CaptureErrorKind::FieldCount {
            expected: 3,
            found: 2
        }
    ));

    let e = insertion(vec![vec![], vec![], vec![]]).unwrap_err();
    assert!(matches!(e.kind, CaptureErrorKind::NoSamples));
    assert_eq!(
        e.to_string(),
        "<memory>: no samples (a capture needs at least one data row)"
    );

    let e = insertion(vec![vec![0.0, 0.1], vec![0.0], vec![0.0, 0.0]]).unwrap_err();
    assert!(matches!(
        e.kind,
        CaptureErrorKind::ColumnLength {
            expected: 2,
            found: 1
        }
    ));
    assert_eq!(
        e.to_string(),
        "<memory>: column `depth_m`: column has 1 samples, expected 2"
    );

    let e = insertion(vec![vec![0.0, 0.1, 0.2], vec![0.0; 3], vec![0.0, 0.0, f64::NAN]]).unwrap_err();
    assert!(matches!(e.kind, CaptureErrorKind::NotFinite));
    assert_eq!(
        e.to_string(),
        "<memory>:5: column `axial_force_n`: value is not finite"
    );

    let e = insertion(vec![vec![0.0, 0.1, 0.1], vec![0.0; 3], vec![0.0; 3]]).unwrap_err();
    assert!(matches!(e.kind, CaptureErrorKind::TimeNotIncreasing { .. }));
    assert_eq!((e.line, e.column.as_deref()), (Some(5), Some("time_s")));

    let e = Capture::new(
        Metadata::new(CaptureKind::Insertion, "d", 1.0),
        strings(&["time_s", "depth_m", "friction_force_n"]),
        vec![vec![0.0]; 3],
    )
    .unwrap_err();
    assert!(matches!(&e.kind, CaptureErrorKind::UnknownColumn(c) if c == "friction_force_n"));
    assert_eq!(e.line, Some(2));

    let e = Capture::new(
        Metadata::new(CaptureKind::Insertion, "d", 1.0).with("bad key", 1),
        strings(&["time_s", "depth_m", "axial_force_n"]),
        vec![vec![0.0]; 3],
    )
    .unwrap_err();
    assert!(matches!(e.kind, CaptureErrorKind::BadMetadata(_)));
    assert_eq!(e.line, Some(1));
}

#[test]
fn files_round_trip_and_report_their_path() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("needle.csv");
    let capture = insertion(vec![vec![0.0, 0.002], vec![-0.001, 0.0], vec![0.0, 0.25]]).unwrap();
    capture.write_file(&path).unwrap();
    let back = Capture::read_file(&path, CaptureKind::Insertion).unwrap();
    assert_eq!(back, capture);
    assert_eq!(back.source(), path);
    assert_eq!(std::fs::read(&path).unwrap(), bytes_of(&capture));

    let e = Capture::read_file(&path, CaptureKind::Rubbing).unwrap_err();
    assert!(matches!(
        e.kind,
        CaptureErrorKind::WrongKind {
            expected: CaptureKind::Rubbing,
            found: CaptureKind::Insertion
        }
    ));
    assert_eq!(e.file.as_deref(), Some(path.as_path()));
    assert_eq!(e.line, Some(1));

    let missing = dir.path().join("missing.csv");
    let e = Capture::read_file(&missing, CaptureKind::Insertion).unwrap_err();
    assert!(matches!(&e.kind, CaptureErrorKind::Io(io) if io.kind() == io::ErrorKind::NotFound));
    assert_eq!((e.file.as_deref(), e.line), (Some(missing.as_path()), None));
    assert!(
        e.to_string()
            .starts_with(&format!("{}: I/O error: ", missing.display()))
    );
}

#[test]
fn write_file_is_atomic() {
    let dir = tempfile::tempdir().unwrap();
    let capture = insertion(vec![vec![0.0], vec![0.0], vec![0.0]]).unwrap();
    let listing = atomic::tests::entries;

    // Directory does not exist: clean typed error, nothing created.
    let target = dir.path().join("no/such/dir/a.csv");
    let e = capture.write_file(&target).unwrap_err();
    assert!(matches!(&e.kind, CaptureErrorKind::Io(io) if io.kind() == io::ErrorKind::NotFound));
    assert_eq!(e.file.as_deref(), Some(target.as_path()));
    assert!(listing(dir.path()).is_empty());

    // Failing at the final rename (target is a directory) leaves no temp file.
    std::fs::create_dir(dir.path().join("a.csv")).unwrap();
    let e = capture.write_file(dir.path().join("a.csv")).unwrap_err();
    assert!(matches!(e.kind, CaptureErrorKind::Io(_)));
    assert_eq!(listing(dir.path()), ["a.csv"]);
    assert!(listing(&dir.path().join("a.csv")).is_empty());

    // A failure while writing keeps the previous file and leaves no temp file.
    let path = dir.path().join("b.csv");
    capture.write_file(&path).unwrap();
    let before = std::fs::read(&path).unwrap();
    let e = write_atomically(&path, |out| -> Result<(), WriteFailure> {
        let mut w = CaptureWriter::with_source(
            out,
            &path,
            capture.metadata(),
            &["time_s", "depth_m", "axial_force_n"],
        )?;
        w.write_row(&[0.0, 0.0, 0.0])?;
        w.write_row(&[0.0, 0.0, 0.0])?; // time does not increase: abort mid-way
        w.finish()?;
        Ok(())
    })
    .map_err(|e| e.0)
    .unwrap_err();
    assert!(matches!(e.kind, CaptureErrorKind::TimeNotIncreasing { .. }));
    assert_eq!(std::fs::read(&path).unwrap(), before);
    assert_eq!(listing(dir.path()), ["a.csv", "b.csv"]);
}

/// Lets a test closure use `?` on both capture and I/O errors.
#[derive(Debug)]
struct WriteFailure(CaptureError);

impl From<CaptureError> for WriteFailure {
    fn from(e: CaptureError) -> Self {
        WriteFailure(e)
    }
}

impl From<io::Error> for WriteFailure {
    fn from(e: io::Error) -> Self {
        WriteFailure(CaptureError::new("<io>", CaptureErrorKind::Io(e)))
    }
}

#[test]
fn streaming_writer_and_capture_agree() {
    let capture = Capture::read_from(EXAMPLE.as_bytes(), "example.csv", None).unwrap();
    let columns: Vec<&str> = capture.columns().iter().map(String::as_str).collect();
    let mut w = CaptureWriter::new(Vec::new(), capture.metadata(), &columns).unwrap();
    for i in 0..capture.len() {
        let row: Vec<f64> = capture.data().iter().map(|c| c[i]).collect();
        w.write_row(&row).unwrap();
    }
    assert_eq!(w.finish().unwrap(), bytes_of(&capture));
}

#[test]
fn readers_refuse_what_the_writer_stores_beyond_the_plausible_magnitude() {
    let capture = insertion(vec![vec![0.0, 0.001], vec![0.0, 0.01], vec![0.5, 2e6]]).unwrap();
    let bytes = bytes_of(&capture);
    let e = Capture::read_from(&bytes[..], "big.csv", None).unwrap_err();
    assert_eq!(
        (e.line, e.column.as_deref()),
        (Some(4), Some("axial_force_n")),
        "{e}"
    );
    assert!(
        matches!(e.kind, CaptureErrorKind::Implausible { value, limit } if value == 2e6 && limit == 1e6),
        "{e}"
    );
    assert!(
        e.to_string()
            .starts_with("big.csv:4: column `axial_force_n`: 2e6 is outside ±1e6"),
        "{e}"
    );
}

// --- Property tests ----------------------------------------------------------

/// Any finite f64: all magnitudes, both zeros, subnormals.
fn finite() -> impl Strategy<Value = f64> {
    use proptest::num::f64::{NEGATIVE, NORMAL, POSITIVE, SUBNORMAL, ZERO};
    POSITIVE | NEGATIVE | NORMAL | SUBNORMAL | ZERO
}

/// Any finite f64 a reader accepts in a column with magnitude `limit`: larger magnitudes are
/// folded in by `%`, which keeps every bit pattern of the mantissa in play.
fn plausible(limit: f64) -> impl Strategy<Value = f64> {
    finite().prop_map(move |v| if v.abs() <= limit { v } else { v % limit })
}

fn arb_kind() -> impl Strategy<Value = CaptureKind> {
    prop_oneof![Just(CaptureKind::Rubbing), Just(CaptureKind::Insertion)]
}

fn arb_metadata(kind: CaptureKind) -> impl Strategy<Value = Metadata> {
    use proptest::num::f64::{NORMAL, POSITIVE, SUBNORMAL};
    (
        "[!-~]{1,12}",
        POSITIVE | NORMAL | SUBNORMAL,
        prop::collection::vec(("[A-Za-z0-9_.-]{1,8}", "[!-~]{1,10}"), 0..6),
    )
        .prop_map(move |(device, rate, extra)| {
            let mut meta = Metadata::new(kind, device, rate);
            for (key, value) in extra {
                if !RESERVED_KEYS.contains(&key.as_str()) && meta.get(&key).is_none() {
                    meta = meta.with(key, value);
                }
            }
            meta
        })
}

/// `time_s`, then the other required columns and a random subset of the
/// optional ones, in random order.
fn arb_columns(kind: CaptureKind) -> impl Strategy<Value = Vec<String>> {
    let optional = kind.optional_columns();
    prop::sample::subsequence(optional, 0..=optional.len())
        .prop_flat_map(move |chosen| {
            let rest: Vec<&str> = kind.required_columns()[1..]
                .iter()
                .copied()
                .chain(chosen)
                .collect();
            Just(rest).prop_shuffle()
        })
        .prop_map(|rest| std::iter::once(TIME_S).chain(rest).map(str::to_owned).collect())
}

/// Strictly increasing finite times (sorted, de-duplicated).
fn arb_times() -> impl Strategy<Value = Vec<f64>> {
    prop::collection::vec(plausible(kind::MAX_TIME_MAGNITUDE_S), 1..25).prop_map(|mut times| {
        times.sort_by(f64::total_cmp);
        times.dedup_by(|a, b| a == b); // also merges -0.0 and 0.0
        times
    })
}

fn arb_capture() -> impl Strategy<Value = Capture> {
    arb_kind()
        .prop_flat_map(|kind| (arb_metadata(kind), arb_columns(kind), arb_times()))
        .prop_flat_map(|(meta, columns, times)| {
            let others = prop::collection::vec(
                prop::collection::vec(plausible(kind::MAX_PHYSICAL_MAGNITUDE), times.len()),
                columns.len() - 1,
            );
            (Just(meta), Just(columns), Just(times), others)
        })
        .prop_map(|(meta, columns, times, others)| {
            let data = std::iter::once(times).chain(others).collect();
            Capture::new(meta, columns, data).expect("generated capture is valid")
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn round_trip_is_bit_identical(capture in arb_capture()) {
        let bytes = bytes_of(&capture);
        prop_assert_eq!(&bytes, &bytes_of(&capture), "writing is deterministic");

        let back = Capture::read_from(&bytes[..], "rt.csv", Some(capture.metadata().kind()))
            .expect("reads back");
        prop_assert_eq!(&back, &capture);
        prop_assert_eq!(back.metadata().rate_hz().to_bits(), capture.metadata().rate_hz().to_bits());
        for (a, b) in back.data().iter().zip(capture.data()) {
            let a: Vec<u64> = a.iter().map(|v| v.to_bits()).collect();
            let b: Vec<u64> = b.iter().map(|v| v.to_bits()).collect();
            prop_assert_eq!(a, b);
        }
        prop_assert_eq!(bytes_of(&back), bytes, "re-writing gives the same bytes");
    }

    #[test]
    fn any_truncation_is_rejected(capture in arb_capture(), cut in any::<prop::sample::Index>()) {
        let bytes = bytes_of(&capture);
        let cut = cut.index(bytes.len()); // strictly shorter than the file
        let result = Capture::read_from(&bytes[..cut], "cut.csv", None);
        // Cutting right after a complete data row yields a shorter valid capture.
        let at_row_boundary = cut > 0
            && bytes[cut - 1] == b'\n'
            && bytes[..cut].iter().filter(|&&b| b == b'\n').count() >= 3;
        if at_row_boundary {
            let shorter = result.expect("prefix of whole rows is valid");
            prop_assert!(shorter.len() < capture.len());
        } else {
            prop_assert!(result.is_err(), "cut at {} of {} accepted", cut, bytes.len());
        }
    }
}

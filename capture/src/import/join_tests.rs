//! Several inputs joined on their own clocks ([`import_streams`]).

use std::fmt::Write as _;
use std::path::PathBuf;

use super::*;

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

fn spec(map: &str, rate_hz: f64) -> ImportSpec {
    let mut spec = ImportSpec::new(CaptureKind::Rubbing, ColumnMap::parse(map).unwrap());
    spec.rate_hz = Some(rate_hz);
    spec
}

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/fixtures/import")
        .join(name)
}

// Straight lines in true time, which linear interpolation and the zero-phase low-pass both
// reproduce, so the joined values must equal them to rounding.
fn force_n(t: f64) -> f64 {
    1.5 + 0.8 * t
}

fn position_m(t: f64) -> f64 {
    0.002 - 0.01 * t
}

fn accel_mps2(t: f64) -> f64 {
    -3.0 + 4.0 * t
}

/// Three logs of one second on three clocks: forces at ~90 Hz jittered from 0 s (time in
/// ms), position at ~70 Hz jittered on a clock 0.25 s behind (time `stamp` in µs), and an
/// accelerometer uniform at 5 kHz from 0.031 s (time in s).
fn three_clocks(dir: &Path) -> [PathBuf; 3] {
    let mut rng = crate::rng::SplitMix64::new(7);
    let mut force = String::from("t,Fz\n");
    let mut t = 0.0;
    while t <= 1.0 {
        let t_ms = (t * 1e3_f64 * 1e3).round() / 1e3;
        writeln!(force, "{t_ms},{}", force_n(t_ms / 1e3)).unwrap();
        t += (0.8 + 0.4 * rng.next_f64()) / 90.0;
    }
    let mut position = String::from("stamp,x\n");
    let mut t = 0.012;
    while t <= 1.02 {
        let t_us = (t * 1e6_f64).round();
        // The stage's clock reads 0.25 s less than the force sensor's.
        writeln!(position, "{},{}", t_us - 250_000.0, position_m(t_us / 1e6) * 1e3).unwrap();
        t += (0.8 + 0.4 * rng.next_f64()) / 70.0;
    }
    let mut accel = String::from("time,ax\n");
    for j in 0..4900 {
        let t = 0.031 + j as f64 / 5000.0;
        writeln!(accel, "{t},{}", accel_mps2(t)).unwrap();
    }
    [
        write(dir, "force.csv", &force),
        write(dir, "position.csv", &position),
        write(dir, "accel.csv", &accel),
    ]
}

const THREE_MAP: &str = "time_s=t[ms],time_s=2:stamp[us],time_s=3:time,normal_force_n=Fz,\
                         tangential_position_m=x[mm],accel_x_mps2=ax";

#[test]
fn streams_are_joined_on_their_own_clocks_over_their_overlap() {
    let dir = tempfile::tempdir().unwrap();
    let paths = three_clocks(dir.path());
    let inputs: Vec<&Path> = paths.iter().map(PathBuf::as_path).collect();
    let mut spec = spec(THREE_MAP, 1000.0);
    spec.clock_offsets_s = vec![(2, 0.25)];
    let imported = import_streams(&inputs, &spec).unwrap();
    let c = &imported.capture;
    assert_eq!(
        c.columns(),
        &[
            "time_s",
            "normal_force_n",
            "tangential_position_m",
            "accel_x_mps2"
        ]
    );
    // The overlap: from the latest first time (the accelerometer's, 0.031 s; the position's
    // is 0.012 s once its clock is corrected) to the earliest last time.
    let first: Vec<f64> = imported.streams.iter().map(|s| s.first_time_s).collect();
    let last: Vec<f64> = imported.streams.iter().map(|s| s.last_time_s).collect();
    assert!((first[1] - 0.012).abs() < 1e-12, "{first:?}");
    assert_eq!(first[2], 0.031);
    let (lo, hi) = (first[2], last.iter().copied().fold(f64::INFINITY, f64::min));
    let time = c.time();
    assert_eq!(time[0], lo);
    assert!(time[time.len() - 1] <= hi && time[time.len() - 1] > hi - 1e-3);
    assert_eq!(time.len(), ((hi - lo) * 1000.0 + 1e-6).floor() as usize + 1);
    for (column, line) in [
        ("normal_force_n", force_n as fn(f64) -> f64),
        ("tangential_position_m", position_m),
        ("accel_x_mps2", accel_mps2),
    ] {
        for (&t, &v) in time.iter().zip(c.column(column).unwrap()) {
            assert!((v - line(t)).abs() < 1e-9, "{column} at {t}: {v} vs {}", line(t));
        }
    }
    for (stream, path) in imported.streams.iter().zip(&paths) {
        assert_eq!(&stream.file, path);
        assert!((stream.cut_start_s - (lo - stream.first_time_s)).abs() < 1e-15);
        assert!((stream.cut_end_s - (stream.last_time_s - hi)).abs() < 1e-15);
        assert_eq!(stream.sha256, crate::sha256_hex(&std::fs::read(path).unwrap()));
    }
    assert_eq!(imported.streams[1].clock_offset_s, 0.25);
    // Each stream resampled by its own rate: the slow ones interpolated, the fast one
    // low-passed on its own 5 kHz grid.
    assert_eq!(imported.streams[0].resampling, Resampling::Interpolated);
    assert_eq!(imported.streams[1].resampling, Resampling::Interpolated);
    assert_eq!(
        imported.streams[2].resampling,
        Resampling::LowPassed {
            cutoff_hz: 400.0,
            intermediate_rate_hz: 5000.0
        }
    );
    assert_eq!(
        imported.rows_in,
        imported.streams.iter().map(|s| s.rows_in).sum::<usize>()
    );
    let m = c.metadata();
    assert_eq!(m.get("source"), Some("force.csv,position.csv,accel.csv"));
    assert_eq!(m.get("source_2"), Some("position.csv"));
    assert_eq!(
        m.get("source_2_map"),
        Some("time_s=2:stamp[us],tangential_position_m=x[mm]")
    );
    assert_eq!(m.get("source_1_map"), Some("time_s=t[ms],normal_force_n=Fz"));
    assert_eq!(m.get("source_2_clock_offset_s"), Some("0.25"));
    assert_eq!(m.get("source_1_clock_offset_s"), None);
    assert_eq!(m.get("source_3_rate_hz"), Some("5000"));
    assert_eq!(m.get("source_rate_hz"), None);

    // Without the offset, the position's clock is 0.25 s off: the same samples land 0.25 s
    // earlier, and the joined position is the line a quarter second later.
    spec.clock_offsets_s.clear();
    let shifted = import_streams(&inputs, &spec).unwrap().capture;
    let (t0, x0) = (
        shifted.time()[0],
        shifted.column("tangential_position_m").unwrap()[0],
    );
    assert!((x0 - position_m(t0 + 0.25)).abs() < 1e-9, "{x0} at {t0}");
}

#[test]
fn the_packed_fixture_stream_keeps_its_rate_and_its_repeated_rows_are_merged() {
    let paths = [
        fixture("multistream_force.csv"),
        fixture("multistream_position.csv"),
        fixture("multistream_vib_packed.csv"),
    ];
    let inputs: Vec<&Path> = paths.iter().map(PathBuf::as_path).collect();
    let mut spec = spec(
        "time_s=t[ms],normal_force_n=Fz,friction_force_n=Fx,tangential_position_m=x[mm],\
         accel_x_mps2=acc[g]",
        1000.0,
    );
    spec.unroll = Some(Unroll::parse("acc=acc_0..acc_21", SlowColumns::Interpolate).unwrap());
    // The force log repeats three timestamps: refused by default, naming the file.
    let error = import_streams(&inputs, &spec).unwrap_err();
    assert_eq!(error.file.as_deref(), Some(inputs[0]));
    assert!(
        matches!(error.kind, CaptureErrorKind::RowTimeNotIncreasing { .. }),
        "{error}"
    );
    spec.repeated_time = RepeatedTime::Mean;
    let imported = import_streams(&inputs, &spec).unwrap();
    let rows_repeated: Vec<usize> = imported.streams.iter().map(|s| s.rows_repeated).collect();
    assert_eq!(rows_repeated, [3, 0, 0]);
    // 293 rows of 22 samples, unrolled; at 2.2 kHz the low-pass runs on the stream's own grid.
    let vib = &imported.streams[2];
    assert_eq!(vib.rows_in, 293 * 22);
    assert_eq!(
        vib.resampling,
        Resampling::LowPassed {
            cutoff_hz: 400.0,
            intermediate_rate_hz: 2200.0
        }
    );
    assert_eq!(vib.map, "time_s=t[ms],accel_x_mps2=acc[g]");
    // The position log starts last (41.7 ms): the others are cut there.
    assert_eq!(imported.capture.time()[0], 0.0417);
    assert!((imported.streams[0].cut_start_s - 0.0417).abs() < 1e-12);
    assert_eq!(imported.streams[1].cut_start_s, 0.0);
}

#[test]
fn a_source_must_be_in_exactly_one_input() {
    let dir = tempfile::tempdir().unwrap();
    let a = write(dir.path(), "a.csv", "t,Fz,x\n0,1,5\n10,2,6\n20,3,7\n30,4,8\n");
    let b = write(dir.path(), "b.csv", "t,x\n0,10\n10,20\n20,30\n30,40\n");
    let inputs = [a.as_path(), b.as_path()];
    let error = import_streams(
        &inputs,
        &spec("time_s=t[ms],normal_force_n=Fz,tangential_position_m=x", 100.0),
    )
    .unwrap_err();
    match &error.kind {
        CaptureErrorKind::SourceInSeveralInputs { column, files, .. } => {
            assert_eq!(&**column, "x");
            assert_eq!(&**files, &[(1, a.clone()), (2, b.clone())]);
        }
        other => panic!("{other:?}"),
    }
    let message = error.to_string();
    assert!(message.contains("a.csv") && message.contains("b.csv") && message.contains("`N:x`"));

    let error = import_streams(
        &inputs,
        &spec("time_s=t[ms],normal_force_n=Fz,tangential_position_m=y", 100.0),
    )
    .unwrap_err();
    match &error.kind {
        CaptureErrorKind::SourceInNoInput { column, inputs, .. } => {
            assert_eq!(&**column, "y");
            assert_eq!(inputs[0].columns, ["t", "Fz", "x"]);
            assert_eq!(inputs[1].columns, ["t", "x"]);
            assert_eq!(inputs[1].file, b);
        }
        other => panic!("{other:?}"),
    }
    assert!(error.to_string().contains("b.csv has t, x"), "{error}");

    // Qualified, `x` comes from input 2 (whose values are not input 1's).
    let c = joined(
        &inputs,
        "time_s=t[ms],normal_force_n=Fz,tangential_position_m=2:x",
    );
    assert_eq!(
        c.column("tangential_position_m").unwrap(),
        &[10.0, 20.0, 30.0, 40.0]
    );
    assert_eq!(c.column("normal_force_n").unwrap(), &[1.0, 2.0, 3.0, 4.0]);

    // Reading `x` from input 1 leaves input 2 nothing but its time: an error, not a file
    // silently ignored.
    let error = import_streams(
        &inputs,
        &spec("time_s=t[ms],normal_force_n=Fz,tangential_position_m=1:x", 100.0),
    )
    .unwrap_err();
    assert_eq!(error.file.as_deref(), Some(b.as_path()));
    assert!(
        error.to_string().contains("input 2: no --map entry reads it"),
        "{error}"
    );
    let error = import_streams(
        &[a.as_path(), b.as_path(), a.as_path()],
        &spec(
            "time_s=t[ms],normal_force_n=1:Fz,tangential_position_m=2:x",
            100.0,
        ),
    )
    .unwrap_err();
    assert_eq!(error.file.as_deref(), Some(a.as_path()));
    assert!(
        error.to_string().contains("input 3: no --map entry reads it"),
        "{error}"
    );
    // An input number beyond the inputs.
    let error = import_streams(
        &inputs,
        &spec("time_s=t[ms],normal_force_n=Fz,tangential_position_m=3:x", 100.0),
    )
    .unwrap_err();
    assert!(error.to_string().contains("there is no input 3"), "{error}");
}

/// The capture `inputs` join into at 100 Hz through `map`.
fn joined(inputs: &[&Path], map: &str) -> Capture {
    import_streams(inputs, &spec(map, 100.0)).unwrap().capture
}

#[test]
fn the_inputs_must_overlap_for_a_few_output_samples() {
    let dir = tempfile::tempdir().unwrap();
    let a = write(dir.path(), "a.csv", "t,Fz\n0,1\n5,2\n10,3\n");
    let far = write(dir.path(), "far.csv", "t,x\n100,1\n105,2\n110,3\n");
    let error = import_streams(
        &[a.as_path(), far.as_path()],
        &spec("time_s=t[ms],normal_force_n=Fz,tangential_position_m=x", 1000.0),
    )
    .unwrap_err();
    match &error.kind {
        CaptureErrorKind::NoOverlap {
            rows,
            ranges,
            min_rows,
            ..
        } => {
            assert_eq!((*rows, *min_rows), (0, MIN_JOINED_ROWS));
            assert_eq!(ranges[1], (far.clone(), 0.1, 0.11));
        }
        other => panic!("{other:?}"),
    }
    assert!(
        error.to_string().contains("far.csv spans 0.1 s to 0.11 s"),
        "{error}"
    );
    // 8 ms to 10 ms at 1 kHz is 3 samples, one short; 7 ms to 10 ms is 4.
    for (start_ms, ok) in [(8, false), (7, true)] {
        let b = write(dir.path(), "b.csv", &format!("t,x\n{start_ms},1\n20,2\n"));
        let result = import_streams(
            &[a.as_path(), b.as_path()],
            &spec("time_s=t[ms],normal_force_n=Fz,tangential_position_m=x", 1000.0),
        );
        assert_eq!(result.is_ok(), ok, "{start_ms} ms: {result:?}");
        if let Ok(imported) = result {
            assert_eq!(imported.capture.len(), MIN_JOINED_ROWS);
        }
    }
}

#[test]
fn joining_options_are_checked_before_reading() {
    let dir = tempfile::tempdir().unwrap();
    let a = write(dir.path(), "a.csv", "t,Fz\n0,1\n10,2\n20,3\n30,4\n");
    let b = write(dir.path(), "b.csv", "s,x\n0,1\n10,2\n20,3\n30,4\n");
    let inputs = [a.as_path(), b.as_path()];
    let map = "time_s=t[ms],time_s=2:s[ms],normal_force_n=Fz,tangential_position_m=x";
    let says = |spec: &ImportSpec, text: &str| {
        let error = import_streams(&inputs, spec).unwrap_err();
        assert!(error.to_string().contains(text), "{error} (expected {text})");
        error
    };
    let mut s = spec(map, 100.0);
    s.rate_hz = None;
    says(&s, "needs the output rate (--rate-hz)");
    let mut s = spec(map, 100.0);
    s.metadata.push(("source_2_sha256".into(), "x".into()));
    says(&s, "set by the import itself");
    let mut s = spec(map, 100.0);
    s.clock_offsets_s = vec![(3, 0.1)];
    says(&s, "there is no input 3");
    s.clock_offsets_s = vec![(2, 0.1), (2, 0.2)];
    says(&s, "input 2 has an offset already");
    s.clock_offsets_s = vec![(1, f64::NAN)];
    says(&s, "must be finite");
    // Input 2's time column is not `t`: without its own entry it has none.
    let error = says(
        &spec("time_s=t[ms],normal_force_n=Fz,tangential_position_m=x", 100.0),
        "column `t`",
    );
    assert_eq!(error.file.as_deref(), Some(b.as_path()));
    // Only input 1 named a time of its own, and there is no shared one.
    let error = says(
        &spec("time_s=1:t[ms],normal_force_n=Fz,tangential_position_m=x", 100.0),
        "input 2: no time column",
    );
    assert_eq!(error.file.as_deref(), Some(b.as_path()));
    assert!(import_streams(&inputs, &spec(map, 100.0)).is_ok());
    assert!(matches!(
        import_streams(&[], &spec(map, 100.0)),
        Err(CaptureError {
            file: None,
            kind: CaptureErrorKind::BadSpec(_),
            ..
        })
    ));
}

#[test]
fn one_input_is_the_single_file_import() {
    let dir = tempfile::tempdir().unwrap();
    let a = write(dir.path(), "a.csv", "t,Fz,x\n0,1,5\n10,2,6\n20,3,7\n");
    let plain = import_csv_report(
        &a,
        &spec("time_s=t[ms],normal_force_n=Fz,tangential_position_m=x", 200.0),
    )
    .unwrap();
    // Qualifying with input 1 changes nothing but the recorded map.
    let qualified = import_streams(
        &[a.as_path()],
        &spec(
            "time_s=1:t[ms],normal_force_n=Fz,tangential_position_m=1:x",
            200.0,
        ),
    )
    .unwrap();
    assert_eq!(plain.capture.time(), qualified.capture.time());
    for column in ["normal_force_n", "tangential_position_m"] {
        assert_eq!(
            plain.capture.column(column).unwrap(),
            qualified.capture.column(column).unwrap()
        );
    }
    assert_eq!(plain.streams.len(), 1);
    assert_eq!(plain.streams[0].cut_start_s, 0.0);
    assert_eq!(plain.streams[0].cut_end_s, 0.0);
    assert_eq!(plain.capture.metadata().get("source_rate_hz"), Some("100"));
    assert_eq!(plain.capture.metadata().get("source_1"), None);
    let mut shifted = spec("time_s=t[ms],normal_force_n=Fz,tangential_position_m=x", 200.0);
    shifted.clock_offsets_s = vec![(1, 2.0)];
    let shifted = import_csv_report(&a, &shifted).unwrap().capture;
    assert_eq!(shifted.time()[0], 2.0);
    assert_eq!(shifted.metadata().get("source_1_clock_offset_s"), Some("2"));
    let error = import_csv_report(
        &a,
        &spec("time_s=t[ms],normal_force_n=Fz,tangential_position_m=2:x", 200.0),
    )
    .unwrap_err();
    assert_eq!(error.file.as_deref(), Some(a.as_path()));
    assert!(error.to_string().contains("there is no input 2"), "{error}");
}

#[test]
fn each_input_may_name_its_own_time_column_once() {
    let m = ColumnMap::parse("time_s=t[ms],time_s=2:stamp[us],normal_force_n=3:Fz").unwrap();
    let inputs: Vec<Option<usize>> = m.entries().iter().map(|e| e.input).collect();
    assert_eq!(inputs, [None, Some(2), Some(3)]);
    assert_eq!(m.entries()[1].source, "stamp");
    for (spec, says) in [
        ("time_s=t,time_s=t2", "mapped more than once"),
        ("time_s=2:t,time_s=2:u", "for input 2"),
        (
            "time_s=t,normal_force_n=Fz,normal_force_n=2:Fz",
            "mapped more than once",
        ),
        ("time_s=0:t", "numbered from 1"),
    ] {
        let error = ColumnMap::parse(spec).unwrap_err();
        assert!(error.to_string().contains(says), "{spec}: {error}");
    }
    // A colon after something other than digits is part of the name.
    assert_eq!(
        ColumnMap::parse("time_s=Time:s").unwrap().entries()[0].source,
        "Time:s"
    );
}

#[test]
fn a_clock_in_other_units_than_the_others_is_refused_with_both_spans() {
    let dir = tempfile::tempdir().unwrap();
    let mut seconds = String::from("t,Fz\n");
    let mut millis = String::from("t,x\n");
    for i in 0..=100 {
        let t = f64::from(i) * 0.01;
        writeln!(seconds, "{t},{}", force_n(t)).unwrap();
        // The same second, its clock counting milliseconds, mapped as seconds.
        writeln!(millis, "{},{}", t * 1e3, position_m(t)).unwrap();
    }
    let a = write(dir.path(), "force.csv", &seconds);
    let b = write(dir.path(), "position.csv", &millis);
    let error = import_streams(
        &[a.as_path(), b.as_path()],
        &spec("time_s=t,normal_force_n=Fz,tangential_position_m=x", 100.0),
    )
    .unwrap_err();
    assert!(
        matches!(&error.kind, CaptureErrorKind::SpansDisagree(m)
            if m.long == b && m.long_s == 1000.0 && m.short_s == 1.0),
        "{error:?}"
    );
    let text = error.to_string();
    assert!(
        text.contains("position.csv spans 1000 s")
            && text.contains("force.csv spans 1 s")
            && text.contains("t[ms]"),
        "{text}"
    );
    // Its unit given, the same files join.
    import_streams(
        &[a.as_path(), b.as_path()],
        &spec(
            "time_s=1:t,normal_force_n=Fz,time_s=2:t[ms],tangential_position_m=x",
            100.0,
        ),
    )
    .unwrap();
}

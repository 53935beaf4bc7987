use std::path::PathBuf;

use super::*;

fn map(spec: &str) -> ColumnMap {
    ColumnMap::parse(spec).unwrap()
}

fn map_err(spec: &str) -> (String, String) {
    match ColumnMap::parse(spec) {
        Err(CaptureError {
            file: None,
            kind: CaptureErrorKind::BadMap { entry, reason },
            ..
        }) => (entry, reason),
        other => panic!("expected BadMap for `{spec}`, got {other:?}"),
    }
}

#[test]
fn parses_units_factors_and_spaces() {
    let m = map(
        " time_s = t[ms] , tangential_position_m=x[mm],normal_force_n=Fz*-0.001, friction_force_n=Fx[mN]*2 ",
    );
    assert_eq!(
        m.spec(),
        "time_s=t[ms],tangential_position_m=x[mm],normal_force_n=Fz*-0.001,friction_force_n=Fx[mN]*2"
    );
    let e = m.entries();
    assert_eq!(e.len(), 4);
    assert_eq!((e[0].target.as_str(), e[0].source.as_str()), ("time_s", "t"));
    assert_eq!(e[0].unit.as_deref(), Some("ms"));
    assert_eq!(e[0].scale.apply(1500.0), 1.5);
    assert_eq!(e[1].scale.apply(1.0), 0.001);
    assert_eq!(e[2].source, "Fz");
    assert_eq!(e[2].unit, None);
    assert_eq!(e[2].scale.apply(300.0), -0.3);
    assert_eq!(e[3].scale.apply(150.0), 0.3);
    assert_eq!(
        m.get("friction_force_n").map(|e| e.text.as_str()),
        Some("friction_force_n=Fx[mN]*2")
    );
    // Source names may contain spaces and odd characters; plain names have no scale.
    let m = map("depth_m=Tip depth (m),axial_force_n=F.axial,time_s=\"t\"");
    assert_eq!(m.entries()[0].source, "Tip depth (m)");
    assert_eq!(m.entries()[0].scale, Scale::IDENTITY);
    assert_eq!(m.entries()[2].source, "\"t\"");
    assert_eq!(map("accel_z_mps2=az[g]").entries()[0].scale.factor(), 9.806_65);
}

#[test]
fn decimal_units_divide_exactly() {
    // 0.1 mm is the correctly rounded 1e-4 m (0.1 * 0.001 would not be).
    assert_eq!(map("depth_m=d[mm]").entries()[0].scale.apply(0.1), 1e-4);
    assert_eq!(map("depth_m=d[um]").entries()[0].scale.apply(3.0), 3e-6);
    assert_eq!(map("depth_m=d[µm]").entries()[0].scale.apply(3.0), 3e-6);
    assert_eq!(map("time_s=t[us]").entries()[0].scale.apply(7.0), 7e-6);
}

#[test]
fn unit_table() {
    let cases = [
        ("m", Quantity::Length, 1.0),
        ("cm", Quantity::Length, 1e-2),
        ("mm", Quantity::Length, 1e-3),
        ("um", Quantity::Length, 1e-6),
        ("µm", Quantity::Length, 1e-6),
        ("s", Quantity::Time, 1.0),
        ("ms", Quantity::Time, 1e-3),
        ("us", Quantity::Time, 1e-6),
        ("N", Quantity::Force, 1.0),
        ("mN", Quantity::Force, 1e-3),
        ("kN", Quantity::Force, 1e3),
        ("m/s", Quantity::Velocity, 1.0),
        ("mm/s", Quantity::Velocity, 1e-3),
        ("m/s2", Quantity::Acceleration, 1.0),
        ("g", Quantity::Acceleration, 9.806_65),
    ];
    for (unit, quantity, factor) in cases {
        let (q, f) = unit_to_si(unit).unwrap();
        assert_eq!(q, quantity, "{unit}");
        assert!((f - factor).abs() <= 1e-15 * factor, "{unit}: {f} vs {factor}");
    }
    for unknown in ["MN", "inch", "", "G", "mm/s3"] {
        assert_eq!(unit_to_si(unknown), None, "{unknown}");
    }
    assert_eq!(
        Quantity::of_column("tangential_velocity_mps"),
        Some(Quantity::Velocity)
    );
    assert_eq!(Quantity::of_column("accel_x_mps2"), Some(Quantity::Acceleration));
    assert_eq!(Quantity::of_column("time_s"), Some(Quantity::Time));
    assert_eq!(Quantity::of_column("depth_m"), Some(Quantity::Length));
    assert_eq!(Quantity::of_column("axial_force_n"), Some(Quantity::Force));
}

#[test]
fn map_errors_name_the_entry_and_reason() {
    let (entry, reason) = map_err("time_s=t,depth_m=d[ft]");
    assert_eq!(entry, "depth_m=d[ft]");
    assert!(
        reason.contains("unknown unit `ft`") && reason.contains("mm"),
        "{reason}"
    );
    let (entry, reason) = map_err("friction_force_n=x[mm]");
    assert_eq!(entry, "friction_force_n=x[mm]");
    assert!(
        reason.contains("length unit") && reason.contains("force"),
        "{reason}"
    );
    let (_, reason) = map_err("time_s=t,time_s=u");
    assert!(reason.contains("`time_s` is mapped more than once"), "{reason}");
    let (entry, reason) = map_err("pressure_pa=p");
    assert_eq!(entry, "pressure_pa=p");
    assert!(
        reason.contains("not a capture column") && reason.contains("depth_m"),
        "{reason}"
    );
    assert!(map_err("time_s").1.contains("expected `target=source`"));
    assert!(map_err("=t").1.contains("no target"));
    assert!(map_err("time_s=").1.contains("no source"));
    assert!(map_err("time_s=[ms]").1.contains("no source"));
    assert!(map_err("time_s=t,,depth_m=d").1.contains("empty entry"));
    assert!(map_err("time_s=t,").1.contains("empty entry"));
    assert!(map_err("").1.contains("empty"));
    assert!(
        map_err("time_s=t*x")
            .1
            .contains("scale factor `x` is not a number")
    );
    assert!(map_err("time_s=t*0").1.contains("non-zero"));
    assert!(map_err("time_s=t*inf").1.contains("finite"));
    assert!(map_err("time_s=t[ms").1.contains("brackets"));
    assert!(map_err("time_s=t]").1.contains("`]` without `[`"));
    let display = ColumnMap::parse("time_s=t[h]").unwrap_err().to_string();
    assert!(
        display.starts_with("--map entry `time_s=t[h]`: unknown unit `h`"),
        "{display}"
    );
}

#[test]
fn delimiter_detection() {
    assert_eq!(
        detect_delimiter(b"# comment; with, stuff\n\na;b;c\n1;2;3\n"),
        b';'
    );
    assert_eq!(detect_delimiter(b"a\tb\tc\n"), b'\t');
    assert_eq!(detect_delimiter(b"\"x;y\",b,c\n"), b',');
    assert_eq!(detect_delimiter(b"a,b;c\n"), b';'); // tie: `;` before `,`
    assert_eq!(detect_delimiter(b"time\n1\n"), b',');
    assert_eq!(detect_delimiter(b""), b',');
}

#[test]
fn interpolation_is_linear_and_exact_at_samples() {
    let t = [0.0, 1.0, 3.0];
    let x = [0.0, 2.0, -2.0];
    assert_eq!(
        interpolate(&t, &x, &[-1.0, 0.0, 0.5, 1.0, 2.0, 3.0, 4.0]),
        vec![0.0, 0.0, 1.0, 2.0, 0.0, -2.0, -2.0]
    );
}

#[test]
fn butterworth_has_the_designed_response() {
    let rate = 10_000.0;
    let f = LowPass::butterworth4(400.0, rate);
    assert!((f.gain(0.0, rate) - 1.0).abs() < 1e-12);
    // −3 dB at the cut-off per pass.
    assert!((f.gain(400.0, rate) - 0.5_f64.sqrt()).abs() < 1e-9);
    // Bilinear 4th order: |H| = 1 / sqrt(1 + (tan(πf/fs) / tan(πfc/fs))^8).
    let ratio = (std::f64::consts::PI * 0.2).tan() / (std::f64::consts::PI * 0.04).tan();
    let expected = 1.0 / (1.0 + ratio.powi(8)).sqrt();
    assert!((f.gain(2000.0, rate) / expected - 1.0).abs() < 1e-6);
    // A constant and a ramp pass unchanged (steady-state start, odd reflection).
    let ramp: Vec<f64> = (0..500).map(|i| 0.3 + 0.01 * i as f64).collect();
    for (a, b) in f.filtfilt(&ramp).iter().zip(&ramp) {
        assert!((a - b).abs() < 1e-9, "{a} vs {b}");
    }
    assert_eq!(f.filtfilt(&[4.0]), vec![4.0]);
    assert!(f.filtfilt(&[1.0, 2.0]).iter().all(|v| v.is_finite()));
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

fn rubbing(spec: &str) -> ImportSpec {
    ImportSpec::new(CaptureKind::Rubbing, map(spec))
}

const RUB_MAP: &str = "time_s=t[ms],tangential_position_m=x[mm],normal_force_n=Fz";

#[test]
fn imports_a_uniform_file_unchanged_with_metadata() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(
        dir.path(),
        "log 1.csv",
        "\u{feff}# exported by a logger\n\"t\";\"x\";\"Fz\";\"other\"\n\n\
         0;1.5;0.3;a\n10;2.5;0.31;b\n20;3.5;0.32;c\r\n",
    );
    let mut spec = rubbing(&format!("{RUB_MAP}, friction_force_n=Fz*0.5"));
    spec.metadata.push(("surface".into(), "sandpaper_400".into()));
    let imported = import_csv_report(&path, &spec).unwrap();
    assert_eq!(imported.resampling, Resampling::PassThrough);
    assert_eq!(imported.rows_in, 3);
    assert_eq!(imported.rate_hz, 100.0);
    let c = imported.capture;
    assert_eq!(
        c.columns(),
        &[
            "time_s",
            "tangential_position_m",
            "normal_force_n",
            "friction_force_n"
        ]
    );
    assert_eq!(c.time(), &[0.0, 0.01, 0.02]);
    assert_eq!(
        c.column("tangential_position_m").unwrap(),
        &[0.0015, 0.0025, 0.0035]
    );
    assert_eq!(c.column("friction_force_n").unwrap(), &[0.15, 0.155, 0.16]);
    let m = c.metadata();
    assert_eq!(
        (m.kind(), m.device(), m.rate_hz()),
        (CaptureKind::Rubbing, "imported", 100.0)
    );
    assert_eq!(m.get("source"), Some("log_1.csv"));
    assert_eq!(
        m.get("map"),
        Some("time_s=t[ms],tangential_position_m=x[mm],normal_force_n=Fz,friction_force_n=Fz*0.5")
    );
    assert_eq!(m.get("source_rate_hz"), Some("100"));
    assert_eq!(m.get("surface"), Some("sandpaper_400"));
}

#[test]
fn time_from_the_input_rate() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "a.tsv", "x\tFz\n1\t0.1\n2\t0.2\n3\t0.3\n4\t0.4\n");
    let mut spec = rubbing("tangential_position_m=x,normal_force_n=Fz");
    assert!(
        matches!(import_csv(&path, &spec), Err(CaptureError { kind: CaptureErrorKind::BadSpec(reason), .. }) if reason.contains("no time"))
    );
    spec.input_rate_hz = Some(4.0);
    spec.rate_hz = Some(8.0);
    let c = import_csv(&path, &spec).unwrap();
    assert_eq!(c.time(), &[0.0, 0.125, 0.25, 0.375, 0.5, 0.625, 0.75]);
    assert_eq!(
        c.column("tangential_position_m").unwrap(),
        &[1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0]
    );
    let mut both = rubbing("time_s=x,tangential_position_m=x,normal_force_n=Fz");
    both.input_rate_hz = Some(4.0);
    assert!(
        import_csv(&path, &both)
            .unwrap_err()
            .to_string()
            .contains("time is given twice")
    );
}

#[test]
fn file_errors_name_file_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let err = |text: &str, spec: &ImportSpec| {
        let path = write(dir.path(), "in.csv", text);
        import_csv(&path, spec).unwrap_err().to_string()
    };
    let spec = rubbing(RUB_MAP);
    let e = err("# c\nt,x,Fz\n0,1,2\n\n1,1x,2\n", &spec);
    assert!(e.ends_with("in.csv:5: column `x`: `1x` is not a number"), "{e}");
    for (text, expected) in [
        (
            "t;x;Fz\n0;1;2\n1;1,5;2\n",
            ":3: column `x`: `1,5` is not a number (decimal commas",
        ),
        ("t,x,Fz\n0,1,\n", ":2: column `Fz`: `` is not a number"),
        ("t,x,Fz\n0,1,2\n1,1,nan\n", ":3: column `Fz`: `nan` is not finite"),
        (
            "t,x,Fz\n0,1,2\n1,1\n",
            ":3: expected 3 fields like the header, found 2",
        ),
        (
            "t,x,Fz\n0,1,2\n2,1,2\n2,1,2\n",
            "in.csv:4: column `t`: time 0.002 s is not after the previous row's 0.002 s",
        ),
    ] {
        let e = err(text, &spec);
        assert!(e.contains(expected), "{e}");
    }
    let e = err("t,x,Fz\n0,1,2\n1,1,2\n0.5,1,2\n", &spec);
    assert!(e.contains(":4:") && e.contains("not after"), "{e}");
    let e = err("t,x,Force\n0,1,2\n", &spec);
    assert!(
        e.contains(
            "--map entry `normal_force_n=Fz`: the input has no column `Fz` (its columns: t, x, Force)"
        ),
        "{e}"
    );
    let e = err("t,x,Fz,Fz\n0,1,2,3\n", &spec);
    assert!(e.contains("2 columns named `Fz`"), "{e}");
    let e = err("# only a comment\n\n", &spec);
    assert!(e.contains("no header row"), "{e}");
    let e = err("t,x,Fz\n0,1,2\n", &spec);
    assert!(e.contains("found 1 data row(s)"), "{e}");
    let e = err("t,x,Fz\n0,1,2\n1,\"2,3\n", &spec);
    assert!(e.contains("in.csv:"), "{e}");
    let e = err("t,x,Fz\n0,1,2\n1,1,2\n3,1,2\n", &spec);
    assert!(
        e.contains("not uniformly sampled") && e.contains("--rate-hz"),
        "{e}"
    );
    let missing = import_csv(Path::new("/nonexistent/in.csv"), &spec)
        .unwrap_err()
        .to_string();
    assert!(
        missing.starts_with("/nonexistent/in.csv: cannot read"),
        "{missing}"
    );
}

#[test]
fn spec_errors_are_reported_before_reading() {
    let path = Path::new("never_read.csv");
    let e = |spec: &ImportSpec| import_csv(path, spec).unwrap_err().to_string();
    let missing = e(&rubbing("time_s=t,friction_force_n=f"));
    assert!(
        missing
            .starts_with("never_read.csv: a rubbing capture needs `tangential_position_m`, `normal_force_n`"),
        "{missing}"
    );
    let wrong = e(&rubbing(&format!("{RUB_MAP},depth_m=d")));
    assert!(
        wrong.contains("column `depth_m` is not allowed in a rubbing capture"),
        "{wrong}"
    );
    let mut spec = rubbing(RUB_MAP);
    spec.rate_hz = Some(-1.0);
    assert!(e(&spec).contains("--rate-hz -1: must be finite and positive"));
    let mut spec = rubbing(RUB_MAP);
    spec.device = "my rig".into();
    assert!(e(&spec).contains("metadata: value of `device`"), "{}", e(&spec));
    let mut spec = rubbing(RUB_MAP);
    spec.metadata.push(("surface".into(), "sand paper".into()));
    assert!(e(&spec).contains("value of `surface`"), "{}", e(&spec));
    let mut spec = rubbing(RUB_MAP);
    spec.metadata.push(("source".into(), "x".into()));
    assert!(e(&spec).contains("`source` is set by the import"), "{}", e(&spec));
    let mut spec = rubbing(RUB_MAP);
    spec.metadata.push(("kind".into(), "x".into()));
    assert!(e(&spec).contains("reserved"), "{}", e(&spec));
}

#[test]
fn metadata_safe_values() {
    assert_eq!(metadata_safe("a b\tc"), "a_b_c");
    assert_eq!(metadata_safe("x[µm]"), "x[um]");
    assert_eq!(metadata_safe("é"), "_");
    assert_eq!(metadata_safe(""), "_");
    assert_eq!(snap_rate(999.999_999_999_7), 1000.0);
    assert_eq!(snap_rate(1000.5), 1000.5);
}

#[test]
fn output_budget_is_checked_before_allocating() {
    let dir = tempfile::tempdir().unwrap();
    // 2 rows, 49 bytes, spanning 10⁵ s: at 1 kHz this would be 10⁸ rows (3.8 GB).
    let path = write(dir.path(), "span.csv", "t,x,Fz\n0,0.001,0.3\n100000,0.002,0.3\n");
    let mut spec = rubbing("time_s=t,tangential_position_m=x,normal_force_n=Fz");
    spec.rate_hz = Some(1000.0);
    let e = import_csv(&path, &spec).unwrap_err();
    let shown = e.to_string();
    assert_eq!(e.file.as_deref(), Some(path.as_path()), "{shown}");
    assert!(
        matches!(&e.kind, CaptureErrorKind::TooManyRows(b)
            if b.rows == 100_000_001.0 && b.rows_in == 2 && b.limit == 2.0 * DEFAULT_MAX_UPSAMPLE),
        "{shown}"
    );
    assert!(
        shown.contains("--max-upsample") && shown.contains("--rate-hz"),
        "{shown}"
    );
    // Raising the factor does not lift the absolute cap.
    spec.max_upsample = 1e9;
    let e = import_csv(&path, &spec).unwrap_err();
    assert!(
        matches!(&e.kind, CaptureErrorKind::TooManyRows(b) if b.limit == MAX_OUTPUT_ROWS as f64),
        "{e}"
    );
    // Within both, upsampling works as before.
    let path = write(dir.path(), "short.csv", "t,x,Fz\n0,0.001,0.3\n1,0.002,0.3\n");
    spec.max_upsample = DEFAULT_MAX_UPSAMPLE;
    assert_eq!(import_csv(&path, &spec).unwrap().len(), 1001);
    spec.max_upsample = 100.0;
    assert!(matches!(
        import_csv(&path, &spec).unwrap_err().kind,
        CaptureErrorKind::TooManyRows(b) if b.rows_in == 2
    ));
    spec.max_upsample = 0.5;
    assert!(
        import_csv(&path, &spec)
            .unwrap_err()
            .to_string()
            .contains("--max-upsample 0.5")
    );
}

#[test]
fn rates_must_be_in_the_documented_range() {
    let path = Path::new("never_read.csv");
    for (rate, input_rate, expected) in [
        (Some(3e7), None, "--rate-hz 30000000: must be from 1 to 100000 Hz"),
        (Some(0.5), None, "--rate-hz 0.5: must be from 1 to 100000 Hz"),
        (
            None,
            Some(1e6),
            "--input-rate-hz 1000000: must be from 1 to 100000 Hz",
        ),
    ] {
        let mut spec = rubbing("tangential_position_m=x,normal_force_n=Fz");
        spec.rate_hz = rate;
        spec.input_rate_hz = input_rate.or(Some(1000.0));
        let e = import_csv(path, &spec).unwrap_err();
        assert!(matches!(e.kind, CaptureErrorKind::BadSpec(_)), "{e}");
        assert!(e.to_string().starts_with("never_read.csv: "), "{e}");
        assert!(e.to_string().contains(expected), "{e}");
    }
}

#[test]
fn implausible_values_are_errors_or_dropped_rows() {
    let dir = tempfile::tempdir().unwrap();
    let text = "t,x,Fx,Fz\n0,1,0.1,0.3\n1,2,1e308,0.3\n2,3,0.1,0.3\n3,4,0.1,nan\n4,5,0.1,0.3\n";
    let path = write(dir.path(), "in.csv", text);
    let map_text = "time_s=t[ms],tangential_position_m=x[mm],normal_force_n=Fz,friction_force_n=Fx";
    let mut spec = rubbing(map_text);
    let e = import_csv(&path, &spec).unwrap_err();
    assert_eq!((e.line, e.column.as_deref()), (Some(3), Some("Fx")), "{e}");
    assert!(
        matches!(&e.kind, CaptureErrorKind::ImplausibleText { text, value, limit, target }
            if &**text == "1e308" && *value == 1e308 && *limit == 1e6
                && &**target == "friction_force_n"),
        "{e}"
    );
    assert!(
        e.to_string()
            .contains("in.csv:3: column `Fx`: `1e308` is 1e308 in SI units"),
        "{e}"
    );
    assert!(e.to_string().contains("--drop-implausible"), "{e}");
    // The limit is on the SI value: 2e9 mm is 2e6 m, 2e8 mm is not.
    let mm = write(dir.path(), "mm.csv", "t,x,Fx,Fz\n0,2e8,0,0\n1,2e9,0,0\n");
    let e = import_csv(&mm, &spec).unwrap_err();
    assert!(
        matches!(&e.kind, CaptureErrorKind::ImplausibleText { value, .. } if *value == 2e6)
            && e.line == Some(3),
        "{e}"
    );
    // Time has its own, larger limit: epoch seconds pass, epoch milliseconds as seconds do not.
    let epoch = write(dir.path(), "epoch.csv", "t,x,Fz\n1.7e12,0,0\n1.7e12,0,0\n");
    let e = import_csv(
        &epoch,
        &rubbing("time_s=t,tangential_position_m=x,normal_force_n=Fz"),
    )
    .unwrap_err();
    assert!(
        matches!(&e.kind, CaptureErrorKind::ImplausibleText { limit, .. } if *limit == 1e10),
        "{e}"
    );

    spec.drop_implausible = true;
    spec.rate_hz = Some(1000.0);
    let imported = import_csv_report(&path, &spec).unwrap();
    assert_eq!((imported.rows_in, imported.rows_dropped), (3, 2));
    let c = imported.capture;
    assert_eq!(c.time(), &[0.0, 0.001, 0.002, 0.003, 0.004]);
    // The dropped rows are bridged by interpolation between the kept ones.
    assert_eq!(c.column("friction_force_n").unwrap(), &[0.1; 5]);
    assert!(c.data().iter().flatten().all(|v| v.abs() <= 1e6));
    // Dropping everything but one row leaves too few.
    let bad = write(
        dir.path(),
        "bad.csv",
        "t,x,Fx,Fz\n0,1,inf,0\n1,1,1e7,0\n2,1,0,0\n",
    );
    assert!(matches!(
        import_csv(&bad, &spec).unwrap_err().kind,
        CaptureErrorKind::TooFewRows(1)
    ));
}

#[test]
fn resampled_output_stays_within_the_limits() {
    let dir = tempfile::tempdir().unwrap();
    // A step from -1e6 to 1e6 N at 1 kHz, downsampled: the low-pass overshoots the step.
    let step = |name: &str, size: f64| {
        let mut text = String::from("t,x,Fz\n");
        for i in 0..400 {
            let force = if i < 200 { -size } else { size };
            text += &format!("{},0,{force}\n", i as f64 / 1000.0);
        }
        write(dir.path(), name, &text)
    };
    let path = step("step.csv", 1e6);
    let mut spec = rubbing("time_s=t,tangential_position_m=x,normal_force_n=Fz");
    spec.rate_hz = Some(100.0);
    let e = import_csv(&path, &spec).unwrap_err();
    assert_eq!(e.column.as_deref(), Some("normal_force_n"), "{e}");
    assert!(
        matches!(e.kind, CaptureErrorKind::Implausible { value, limit } if value.abs() > limit),
        "{e}"
    );
    // The same step at half the size comes through.
    let path = step("half.csv", 5e5);
    assert_eq!(import_csv(&path, &spec).unwrap().len(), 40);
}

#[test]
fn a_trailing_delimiter_is_ignored_with_or_without_one_on_the_header() {
    let dir = tempfile::tempdir().unwrap();
    for (name, text) in [
        ("both.csv", "t,x,Fz,\n0,1,0.3,\n10,2,0.4,\n20,3,0.5,\n"),
        ("rows.csv", "t,x,Fz\n0,1,0.3,\n10,2,0.4,\n20,3,0.5,\n"),
        ("header.csv", "t,x,Fz,\n0,1,0.3\n10,2,0.4\n20,3,0.5\n"),
    ] {
        let path = write(dir.path(), name, text);
        let c = import_csv(&path, &rubbing(RUB_MAP)).unwrap();
        assert_eq!(c.column("normal_force_n").unwrap(), &[0.3, 0.4, 0.5], "{name}");
    }
    // Without a header the first row's empty last field is the delimiter's, not column `3`.
    let path = write(dir.path(), "numbered.csv", "0,1,0.3,\n10,2,0.4,\n20,3,0.5,\n");
    let mut spec = rubbing("time_s=0[ms],tangential_position_m=1[mm],normal_force_n=2");
    spec.header = Header::Numbered;
    assert_eq!(import_csv(&path, &spec).unwrap().len(), 3);
    spec.map = map("time_s=0[ms],tangential_position_m=1[mm],normal_force_n=3");
    let e = import_csv(&path, &spec).unwrap_err();
    assert!(matches!(e.kind, CaptureErrorKind::UnknownSource { .. }), "{e}");
}

#[test]
fn a_trailing_field_must_be_empty_and_on_every_row() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "value.csv", "t,x,Fz\n0,1,0.3,\n10,2,0.4,9\n");
    let e = import_csv(&path, &rubbing(RUB_MAP)).unwrap_err();
    assert!(
        matches!(
            e.kind,
            CaptureErrorKind::HeaderFieldCount {
                expected: 3,
                found: 4
            }
        ),
        "{e}"
    );
    assert_eq!(
        (e.line, e.column.as_deref()),
        (Some(3), Some("field 4 (after the last named column)"))
    );
    // The first row decides; a later row without the delimiter does not match it.
    let path = write(dir.path(), "mixed.csv", "t,x,Fz\n# note\n0,1,0.3,\n10,2,0.4\n");
    let e = import_csv(&path, &rubbing(RUB_MAP)).unwrap_err();
    assert!(
        matches!(
            e.kind,
            CaptureErrorKind::HeaderFieldCount {
                expected: 4,
                found: 3
            }
        ),
        "{e}"
    );
    assert_eq!(e.line, Some(4));
    // Two extra fields are not a trailing delimiter.
    let path = write(dir.path(), "two.csv", "t,x,Fz\n0,1,0.3,,\n10,2,0.4,,\n");
    let e = import_csv(&path, &rubbing(RUB_MAP)).unwrap_err();
    assert!(matches!(e.kind, CaptureErrorKind::HeaderFieldCount { .. }), "{e}");
    assert_eq!(e.line, Some(2));
}

#[test]
fn a_header_less_file_takes_names_or_indices_and_a_numeric_header_gets_a_hint() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "raw.csv", "# rig 3\n\n0;1;0.3\n10;2;0.4\n20;3;0.5\n");
    let e = import_csv(&path, &rubbing(RUB_MAP)).unwrap_err();
    assert_eq!(e.line, Some(3), "{e}");
    match &e.kind {
        CaptureErrorKind::BadMap { entry, reason } => {
            assert_eq!(entry, "time_s=t[ms]");
            assert!(reason.contains("`0,1,0.3` looks like data"), "{reason}");
            assert!(
                reason.contains("--no-header") && reason.contains("--columns"),
                "{reason}"
            );
        }
        other => panic!("{other:?}"),
    }

    let mut spec = rubbing(RUB_MAP);
    spec.header = Header::Named(vec!["t".into(), " x ".into(), "Fz".into()]);
    let imported = import_csv_report(&path, &spec).unwrap();
    assert_eq!(imported.rows_in, 3);
    assert_eq!(imported.capture.time(), &[0.0, 0.01, 0.02]);
    assert_eq!(
        imported.capture.column("tangential_position_m").unwrap(),
        &[0.001, 0.002, 0.003]
    );

    spec.header = Header::Numbered;
    spec.map = map("time_s=0[ms],tangential_position_m=1[mm],normal_force_n=2");
    let numbered = import_csv(&path, &spec).unwrap();
    assert_eq!(numbered.time(), imported.capture.time());
    assert_eq!(
        numbered.column("normal_force_n").unwrap(),
        imported.capture.column("normal_force_n").unwrap()
    );

    // A header of names that is missing a column gets no hint.
    let path = write(dir.path(), "named.csv", "t,x,F\n0,1,0.3\n10,2,0.4\n");
    let e = import_csv(&path, &rubbing(RUB_MAP)).unwrap_err();
    assert!(matches!(e.kind, CaptureErrorKind::UnknownSource { .. }), "{e}");

    let mut spec = rubbing(RUB_MAP);
    spec.header = Header::Named(vec!["t".into(), String::new(), "Fz".into()]);
    let e = import_csv(&path, &spec).unwrap_err();
    assert!(
        matches!(&e.kind, CaptureErrorKind::BadSpec(r) if r.contains("--columns")),
        "{e}"
    );
    spec.header = Header::Named(["t", "x", "Fz", "Fx"].map(String::from).to_vec());
    let e = import_csv(&path, &spec).unwrap_err();
    assert!(
        matches!(&e.kind, CaptureErrorKind::BadSpec(r) if r.contains("this row has 3 fields")),
        "{e}"
    );
    assert_eq!(e.line, Some(1));
}

#[test]
fn repeated_times_merge_into_their_mean_or_keep_the_first() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(
        dir.path(),
        "repeat.csv",
        "t,x,Fz\n0,1,0.3\n0,3,0.5\n0,5,0.7\n10,2,0.4\n20,3,0.5\n20,4,0.6\n",
    );
    let e = import_csv(&path, &rubbing(RUB_MAP)).unwrap_err();
    assert!(
        matches!(e.kind, CaptureErrorKind::RowTimeNotIncreasing { .. }),
        "{e}"
    );
    assert_eq!(e.line, Some(3));

    let mut spec = rubbing(RUB_MAP);
    spec.repeated_time = RepeatedTime::Mean;
    let imported = import_csv_report(&path, &spec).unwrap();
    assert_eq!((imported.rows_in, imported.rows_repeated), (3, 3));
    assert_eq!(imported.capture.time(), &[0.0, 0.01, 0.02]);
    let x = imported.capture.column("tangential_position_m").unwrap();
    assert!(
        x.iter()
            .zip([0.003, 0.002, 0.0035])
            .all(|(a, b)| (a - b).abs() < 1e-15),
        "{x:?}"
    );

    spec.repeated_time = RepeatedTime::Drop;
    let imported = import_csv_report(&path, &spec).unwrap();
    assert_eq!((imported.rows_in, imported.rows_repeated), (3, 3));
    assert_eq!(
        imported.capture.column("normal_force_n").unwrap(),
        &[0.3, 0.4, 0.5]
    );

    // Only equal times merge: a time going back is still refused, at its line.
    let path = write(
        dir.path(),
        "back.csv",
        "t,x,Fz\n0,1,0.3\n10,2,0.4\n10,2,0.4\n5,3,0.5\n",
    );
    let e = import_csv(&path, &spec).unwrap_err();
    assert!(
        matches!(e.kind, CaptureErrorKind::RowTimeNotIncreasing { .. }),
        "{e}"
    );
    assert_eq!(e.line, Some(5));

    "mean".parse::<RepeatedTime>().unwrap();
    assert!("average".parse::<RepeatedTime>().is_err());
    let mut spec = rubbing("tangential_position_m=x[mm],normal_force_n=Fz");
    spec.input_rate_hz = Some(100.0);
    spec.repeated_time = RepeatedTime::Mean;
    let e = import_csv(&path, &spec).unwrap_err();
    assert!(
        matches!(&e.kind, CaptureErrorKind::BadSpec(r) if r.contains("--repeated-time")),
        "{e}"
    );
}

#[test]
fn non_finite_cells_are_errors_dropped_or_bridged() {
    let dir = tempfile::tempdir().unwrap();
    let text = "t,x,Fz\n0,0,1\n1,1,nan\n2,2,inf\n3,3,4\n4,4,5\n";
    let path = write(dir.path(), "in.csv", text);
    let mut spec = rubbing(RUB_MAP);
    spec.rate_hz = Some(1000.0);
    let e = import_csv(&path, &spec).unwrap_err();
    assert_eq!((e.line, e.column.as_deref()), (Some(3), Some("Fz")), "{e}");
    assert!(e.to_string().contains("--non-finite drop"), "{e}");

    spec.non_finite = Some(NonFinite::Drop);
    let imported = import_csv_report(&path, &spec).unwrap();
    assert_eq!(
        (
            imported.rows_in,
            imported.rows_dropped,
            imported.rows_non_finite,
            imported.cells_bridged
        ),
        (3, 2, 2, 0)
    );

    spec.non_finite = Some(NonFinite::Bridge);
    let imported = import_csv_report(&path, &spec).unwrap();
    assert_eq!(
        (imported.rows_in, imported.rows_dropped, imported.cells_bridged),
        (5, 0, 2)
    );
    // Linear in time between 1 N at 0 ms and 4 N at 3 ms.
    let force = imported.capture.column("normal_force_n").unwrap();
    for (got, want) in force.iter().zip([1.0, 2.0, 3.0, 4.0, 5.0]) {
        assert!((got - want).abs() < 1e-12, "{force:?}");
    }
    // The bridge follows time, not row count: uneven times give uneven steps.
    let uneven = write(dir.path(), "uneven.csv", "t,x,Fz\n0,0,0\n1,0,nan\n4,0,4\n5,0,5\n");
    let imported = import_csv_report(&uneven, &spec).unwrap();
    let force = imported.capture.column("normal_force_n").unwrap();
    assert!((force[1] - 1.0).abs() < 1e-12, "{force:?}");
}

#[test]
fn bridges_are_short_inside_the_file_and_never_in_time() {
    let dir = tempfile::tempdir().unwrap();
    let mut spec = rubbing(RUB_MAP);
    spec.rate_hz = Some(1000.0);
    spec.non_finite = Some(NonFinite::Bridge);
    let mut long = String::from("t,x,Fz\n0,0,0\n");
    for i in 1..=(MAX_BRIDGE_ROWS + 1) {
        long += &format!("{i},0,nan\n");
    }
    long += &format!("{},0,1\n", MAX_BRIDGE_ROWS + 2);
    let cases = [
        (
            "long.csv",
            long.as_str(),
            3,
            "Fz",
            "11 consecutive non-finite values (line 3 to 13)",
        ),
        (
            "first.csv",
            "t,x,Fz\n0,0,nan\n1,0,1\n2,0,2\n",
            2,
            "Fz",
            "file's first row",
        ),
        (
            "last.csv",
            "t,x,Fz\n0,0,0\n1,0,1\n2,0,inf\n",
            4,
            "Fz",
            "file's last row",
        ),
        (
            "time.csv",
            "t,x,Fz\n0,0,0\nnan,0,1\n2,0,2\n",
            3,
            "t",
            "the row's time",
        ),
    ];
    for (name, text, line, column, needle) in cases {
        let e = import_csv(&write(dir.path(), name, text), &spec).unwrap_err();
        assert!(matches!(e.kind, CaptureErrorKind::CannotBridge(_)), "{e}");
        assert_eq!((e.line, e.column.as_deref()), (Some(line), Some(column)), "{e}");
        assert!(e.to_string().contains(needle), "{name}: {e}");
    }
    // Exactly the limit is bridged.
    let mut edge = String::from("t,x,Fz\n0,0,0\n");
    for i in 1..=MAX_BRIDGE_ROWS {
        edge += &format!("{i},0,nan\n");
    }
    edge += &format!("{},0,11\n", MAX_BRIDGE_ROWS + 1);
    let imported = import_csv_report(&write(dir.path(), "edge.csv", &edge), &spec).unwrap();
    assert_eq!(imported.cells_bridged, MAX_BRIDGE_ROWS);
}

#[test]
fn drop_implausible_and_non_finite_are_separate_choices() {
    let dir = tempfile::tempdir().unwrap();
    let text = "t,x,Fz\n0,0,1\n1,0,1e9\n2,0,nan\n3,0,4\n";
    let path = write(dir.path(), "in.csv", text);
    let mut spec = rubbing(RUB_MAP);
    spec.rate_hz = Some(1000.0);
    spec.drop_implausible = true;
    // Unset, --non-finite follows --drop-implausible: both rows go.
    let imported = import_csv_report(&path, &spec).unwrap();
    assert_eq!((imported.rows_dropped, imported.rows_non_finite), (2, 1));
    // Given, it decides about the NaN alone.
    spec.non_finite = Some(NonFinite::Bridge);
    let imported = import_csv_report(&path, &spec).unwrap();
    assert_eq!((imported.rows_dropped, imported.cells_bridged), (1, 1));
    spec.non_finite = Some(NonFinite::Error);
    let e = import_csv(&path, &spec).unwrap_err();
    assert!(
        matches!(e.kind, CaptureErrorKind::NotFiniteText(_)) && e.line == Some(4),
        "{e}"
    );
    // A row with both is dropped as implausible, whatever the order of the map.
    let both = write(dir.path(), "both.csv", "t,x,Fz\n0,0,0\n1,nan,1e9\n2,0,2\n");
    let imported = import_csv_report(&both, &spec).unwrap();
    assert_eq!((imported.rows_dropped, imported.rows_non_finite), (1, 0));
    assert_eq!("bridge".parse::<NonFinite>(), Ok(NonFinite::Bridge));
    assert!("nan".parse::<NonFinite>().is_err());
}

/// A uniform log at `rate_hz`, 200 rows of a 50 Hz sine.
fn log_at(dir: &Path, name: &str, rate_hz: f64) -> PathBuf {
    let mut text = String::from("t,x,Fz\n");
    for i in 0..200 {
        let t = i as f64 / rate_hz;
        text += &format!("{t},0,{}\n", (2.0 * std::f64::consts::PI * 50.0 * t).sin());
    }
    write(dir, name, &text)
}

#[test]
fn rates_within_the_tolerance_take_the_same_path() {
    let dir = tempfile::tempdir().unwrap();
    let mut spec = rubbing("time_s=t,tangential_position_m=x,normal_force_n=Fz");
    spec.rate_hz = Some(2200.0);
    let slow = import_csv_report(&log_at(dir.path(), "slow.csv", 2199.8), &spec).unwrap();
    let fast = import_csv_report(&log_at(dir.path(), "fast.csv", 2200.1), &spec).unwrap();
    assert_eq!(slow.resampling, Resampling::Interpolated);
    assert_eq!(fast.resampling, Resampling::Interpolated);
    let (a, b) = (
        slow.capture.column("normal_force_n").unwrap(),
        fast.capture.column("normal_force_n").unwrap(),
    );
    let n = a.len().min(b.len());
    assert!(n >= 198, "{n}");
    let worst = a[..n]
        .iter()
        .zip(&b[..n])
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-2, "{worst}");
    // Beyond the tolerance the direction decides: faster is low-passed, slower interpolated.
    let faster = import_csv_report(&log_at(dir.path(), "faster.csv", 2230.0), &spec).unwrap();
    assert!(
        matches!(faster.resampling, Resampling::LowPassed { .. }),
        "{:?}",
        faster.resampling
    );
    let slower = import_csv_report(&log_at(dir.path(), "slower.csv", 2170.0), &spec).unwrap();
    assert_eq!(slower.resampling, Resampling::Interpolated);
}

#[test]
fn time_from_position_at_a_known_speed() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(
        dir.path(),
        "curve.csv",
        "depth_mm,force_N\n0,0\n0.5,0.1\n1,0.3\n1.5,0.2\n2,0.6\n",
    );
    let insertion = |map_text: &str| ImportSpec::new(CaptureKind::Insertion, map(map_text));
    let mut spec = insertion("depth_m=depth_mm[mm],axial_force_n=force_N");
    spec.time_from_position = Some(TimeFromPosition::new("depth_mm[mm]", 0.005).unwrap());
    spec.rate_hz = Some(100.0);
    let imported = import_csv_report(&path, &spec).unwrap();
    let c = &imported.capture;
    // 2 mm at 5 mm/s is 0.4 s: 41 samples at 100 Hz, depth 0.05 mm per sample.
    assert_eq!(c.len(), 41);
    let depth = c.column("depth_m").unwrap();
    assert!(
        (depth[10] - 0.5e-3).abs() < 1e-12 && (depth[40] - 2e-3).abs() < 1e-12,
        "{depth:?}"
    );
    assert_eq!(c.metadata().get("time_from"), Some("depth_mm[mm]@0.005mps"));
    assert!((imported.source_rate_hz - 10.0).abs() < 1e-9);

    // Withdrawal: the position decreases, so the speed is negative.
    let back = write(dir.path(), "back.csv", "depth_mm,force_N\n2,0\n1,0.1\n0,0.2\n");
    spec.time_from_position = Some(TimeFromPosition::new("depth_mm[mm]", -0.005).unwrap());
    assert_eq!(import_csv(&back, &spec).unwrap().len(), 41);
    // Against the stroke: an error naming the line, in positions.
    let e = import_csv(&path, &spec).unwrap_err();
    assert!(
        matches!(e.kind, CaptureErrorKind::PositionNotMonotonic { .. }),
        "{e}"
    );
    assert_eq!((e.line, e.column.as_deref()), (Some(3), Some("depth_mm")), "{e}");
    assert!(
        e.to_string().contains("position 0.0005 m does not advance"),
        "{e}"
    );

    // The unit is required and must be a length; the speed non-zero; time given once.
    for (column, speed, needle) in [
        ("depth_mm", 0.005, "unit in brackets"),
        ("depth_mm[ms]", 0.005, "not a length unit"),
        ("depth_mm[mm]", 0.0, "finite and non-zero"),
        ("[mm]", 0.005, "no column name"),
    ] {
        let e = TimeFromPosition::new(column, speed).unwrap_err();
        assert!(e.to_string().contains(needle), "{column}: {e}");
    }
    let mut twice = insertion("time_s=depth_mm,depth_m=depth_mm[mm],axial_force_n=force_N");
    twice.time_from_position = Some(TimeFromPosition::new("depth_mm[mm]", 0.005).unwrap());
    assert!(
        import_csv(&path, &twice)
            .unwrap_err()
            .to_string()
            .contains("given twice")
    );
}

const PACKED: &str = "t,x,Fz,a_0,a_1,a_2,a_3\n\
                      0,1,0.1,0,1,2,3\n\
                      4,2,0.5,4,5,6,7\n\
                      12,3,0.9,8,9,10,11\n";

fn packed(slow: SlowColumns) -> ImportSpec {
    let mut spec = rubbing("time_s=t[ms],tangential_position_m=x[mm],normal_force_n=Fz,accel_x_mps2=acc");
    spec.unroll = Some(Unroll::parse("acc=a_0..a_3", slow).unwrap());
    spec
}

#[test]
fn unroll_parses_ranges_and_rejects_bad_ones() {
    let u = Unroll::parse(" acc = acc_0..acc_3 ", SlowColumns::Hold).unwrap();
    assert_eq!(u.name, "acc");
    assert_eq!(u.columns, ["acc_0", "acc_1", "acc_2", "acc_3"]);
    assert_eq!(u.slow, SlowColumns::Hold);
    let padded = Unroll::parse("v=ch08..ch11", SlowColumns::Interpolate).unwrap();
    assert_eq!(padded.columns, ["ch08", "ch09", "ch10", "ch11"]);
    assert_eq!(
        Unroll::parse("v=3..5", SlowColumns::Hold).unwrap().columns,
        ["3", "4", "5"]
    );
    for (text, reason) in [
        ("acc_0..acc_3", "expected NAME=PREFIX_0..PREFIX_N"),
        ("=a_0..a_3", "no virtual column name"),
        ("acc=a_0-a_3", "expected NAME=PREFIX_0..PREFIX_N"),
        ("acc=a_x..a_3", "must end in a number"),
        ("acc=a_0..b_3", "different prefixes `a_` and `b_`"),
        ("acc=a_3..a_3", "at least two columns"),
        ("acc=a_0..a_99999", "at most 10000"),
        ("a_1=a_0..a_3", "also one of the packed columns"),
    ] {
        let e = Unroll::parse(text, SlowColumns::Interpolate)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(&format!("--unroll `{text}`")) && e.contains(reason),
            "{text}: {e}"
        );
    }
    assert_eq!("hold".parse(), Ok(SlowColumns::Hold));
    assert_eq!("interpolate".parse(), Ok(SlowColumns::Interpolate));
    assert!("linear".parse::<SlowColumns>().is_err());
}

#[test]
fn packed_rows_unroll_over_each_rows_interval() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "packed.csv", PACKED);
    // Rows 4 ms then 8 ms apart; the last row spans the median interval, 6 ms.
    let expected_time: [f64; 12] = [0.0, 1.0, 2.0, 3.0, 4.0, 6.0, 8.0, 10.0, 12.0, 13.5, 15.0, 16.5];
    let close =
        |a: &[f64], b: &[f64]| a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12);

    let mut spec = packed(SlowColumns::Interpolate);
    spec.rate_hz = Some(2000.0);
    let imported = import_csv_report(&path, &spec).unwrap();
    assert_eq!(imported.rows_in, 12);
    assert_eq!(imported.resampling, Resampling::Interpolated);
    let c = &imported.capture;
    assert_eq!(
        c.columns(),
        &[
            "time_s",
            "tangential_position_m",
            "normal_force_n",
            "accel_x_mps2"
        ]
    );
    // 0 to 16.5 ms at 2 kHz; the accelerometer's samples at their unrolled times.
    assert_eq!(c.len(), 34);
    let acc = c.column("accel_x_mps2").unwrap();
    for (i, &t_ms) in expected_time.iter().enumerate() {
        let k = (t_ms * 2.0).round() as usize;
        assert!((c.time()[k] - t_ms * 1e-3).abs() < 1e-12);
        assert!(
            (acc[k] - i as f64).abs() < 1e-9,
            "sample {i} at {t_ms} ms: {}",
            acc[k]
        );
    }
    // The force is a line between rows; the last row holds.
    let fz = c.column("normal_force_n").unwrap();
    assert!(
        (fz[2] - 0.2).abs() < 1e-12 && (fz[16] - 0.7).abs() < 1e-12,
        "{fz:?}"
    );
    assert!((fz[33] - 0.9).abs() < 1e-12, "{fz:?}");

    // Held: each row's samples take its value; the packed samples are unchanged.
    let mut spec = packed(SlowColumns::Hold);
    spec.rate_hz = Some(2000.0);
    let c = import_csv(&path, &spec).unwrap();
    let fz = c.column("normal_force_n").unwrap();
    assert!(
        close(
            &[fz[2], fz[6], fz[8], fz[16], fz[24], fz[33]],
            &[0.1, 0.1, 0.5, 0.5, 0.9, 0.9]
        ),
        "{fz:?}"
    );
    assert!(close(
        &expected_time.map(|t| c.column("accel_x_mps2").unwrap()[(t * 2.0).round() as usize]),
        &std::array::from_fn::<f64, 12, _>(|i| i as f64)
    ));
}

#[test]
fn packed_rows_errors_name_file_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let err = |name: &str, text: &str, spec: &ImportSpec| {
        let path = write(dir.path(), name, text);
        import_csv(&path, spec).unwrap_err()
    };
    let spec = packed(SlowColumns::Interpolate);

    // A packed column missing from the header.
    let e = err("missing.csv", &PACKED.replacen(",a_2,", ",b_2,", 1), &spec);
    assert!(matches!(e.kind, CaptureErrorKind::UnknownSource { .. }), "{e}");
    let text = e.to_string();
    assert!(text.contains("missing.csv") && text.contains("`a_2`"), "{text}");

    // A column past the range would be a sample left out.
    let wider = "t,x,Fz,a_0,a_1,a_2,a_3,a_4\n0,1,0.1,0,1,2,3,4\n4,2,0.5,4,5,6,7,8\n";
    let text = err("wider.csv", wider, &spec).to_string();
    assert!(
        text.contains("wider.csv") && text.contains("column `a_4`, next to the range"),
        "{text}"
    );

    // A row with fewer packed samples than the header.
    let short = "t,x,Fz,a_0,a_1,a_2,a_3\n0,1,0.1,0,1,2,3\n4,2,0.5,4,5,6\n";
    let e = err("short.csv", short, &spec);
    assert_eq!(e.line, Some(3), "{e}");
    assert!(
        matches!(
            e.kind,
            CaptureErrorKind::HeaderFieldCount {
                expected: 7,
                found: 6
            }
        ),
        "{e}"
    );

    // An empty packed cell.
    let empty = "t,x,Fz,a_0,a_1,a_2,a_3\n0,1,0.1,0,1,2,3\n4,2,0.5,4,,6,7\n";
    let e = err("empty.csv", empty, &spec);
    assert_eq!((e.line, e.column.as_deref()), (Some(3), Some("a_1")), "{e}");

    // Row times that go back.
    let back = "t,x,Fz,a_0,a_1,a_2,a_3\n0,1,0.1,0,1,2,3\n4,2,0.5,4,5,6,7\n3,3,0.9,8,9,10,11\n";
    let e = err("back.csv", back, &spec);
    assert_eq!((e.line, e.column.as_deref()), (Some(4), Some("t")), "{e}");
    assert!(
        matches!(e.kind, CaptureErrorKind::RowTimeNotIncreasing { .. }),
        "{e}"
    );

    // The virtual name clashing with a real column, no map entry reading it, no time column.
    let clash = "t,x,Fz,acc,a_0,a_1,a_2,a_3\n0,1,0.1,9,0,1,2,3\n4,2,0.5,9,4,5,6,7\n";
    let text = err("clash.csv", clash, &spec).to_string();
    assert!(text.contains("already has a column `acc`"), "{text}");
    let mut unused = rubbing("time_s=t[ms],tangential_position_m=x[mm],normal_force_n=Fz");
    unused.unroll = spec.unroll.clone();
    let text = err("unused.csv", PACKED, &unused).to_string();
    assert!(text.contains("no --map entry reads `acc`"), "{text}");
    let mut no_time = rubbing("tangential_position_m=x[mm],normal_force_n=Fz,accel_x_mps2=acc");
    no_time.unroll = spec.unroll.clone();
    no_time.input_rate_hz = Some(100.0);
    let text = err("no_time.csv", PACKED, &no_time).to_string();
    assert!(text.contains("needs a time column"), "{text}");
}

#[test]
fn a_header_that_carries_its_units_is_matched_by_the_same_name_and_unit() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(
        dir.path(),
        "log.csv",
        "t[ms];depth [mm];F[mN]\n0;-1;0\n10;0.5;20\n20;1.5;40\n",
    );
    let mut spec = ImportSpec::new(
        CaptureKind::Insertion,
        map("time_s=t[ms],depth_m=depth[mm],axial_force_n=F[mN]"),
    );
    spec.rate_hz = Some(100.0);
    let c = import_csv_report(&path, &spec).unwrap().capture;
    let near = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12);
    assert!(near(c.column("depth_m").unwrap(), &[-0.001, 0.0005, 0.0015]));
    assert!(near(c.column("axial_force_n").unwrap(), &[0.0, 0.02, 0.04]));
}

//! `palpus import`: researchers' CSV logs become captures (column map, units, resampling).

#![allow(clippy::unwrap_used)] // A failed unwrap is a failed test.
#![allow(clippy::print_stdout)] // The measured errors and attenuations are this test's report.

use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::Path;

use crate::common::{palpus, succeeds, success, text};
use capture::{Capture, CaptureKind};

/// Runs `palpus import IN --kind rubbing --out OUT ARGS...` and returns the output.
fn import(input: &Path, out: &Path, args: &[&str]) -> std::process::Output {
    let mut all = vec![
        "import",
        input.to_str().unwrap(),
        "--kind",
        "rubbing",
        "--out",
        out.to_str().unwrap(),
    ];
    all.extend_from_slice(args);
    palpus(&all)
}

// The analytic test signals, SI units: slow motion and load plus a 2 kHz tool vibration.
const HF_HZ: f64 = 2000.0;
const POS_AMPLITUDE_M: f64 = 0.01;
const POS_HF_M: f64 = 5e-4;
const FORCE_MEAN_N: f64 = 0.3;
const FORCE_AMPLITUDE_N: f64 = 0.1;
const FORCE_HF_N: f64 = 0.02;

fn position_lf(t: f64) -> f64 {
    POS_AMPLITUDE_M * (2.0 * PI * 3.0 * t).sin()
}

fn force_lf(t: f64) -> f64 {
    FORCE_MEAN_N + FORCE_AMPLITUDE_N * (2.0 * PI * 7.0 * t + 0.5).sin()
}

/// The 2 kHz component, phased so that sampling it on a 1 kHz grid starting at `t0` would
/// give its full amplitude as a constant: the worst case of aliasing.
fn hf(t: f64, t0: f64) -> f64 {
    (2.0 * PI * HF_HZ * (t - t0) + PI / 2.0).sin()
}

/// Largest |a − b| over the output samples at least `margin_s` from both ends.
fn max_error(capture: &Capture, column: &str, expected: impl Fn(f64) -> f64, margin_s: f64) -> f64 {
    let time = capture.time();
    let (start, end) = (time[0] + margin_s, time[time.len() - 1] - margin_s);
    time.iter()
        .zip(capture.column(column).unwrap())
        .filter(|(t, _)| (start..=end).contains(*t))
        .map(|(&t, &v)| (v - expected(t)).abs())
        .fold(0.0, f64::max)
}

/// Measured by [`downsample`]: the largest errors away from the ends, and what is left of
/// the 2 kHz vibration relative to its amplitude.
struct Downsampled {
    pos_error_m: f64,
    force_error_n: f64,
    pos_residual: f64,
    force_residual: f64,
    /// Largest position error within 0, 5, 10 and 20 ms of the ends, as a fraction of the
    /// vibration's amplitude.
    pos_edge_residuals: [f64; 4],
}

/// Writes a 10 kHz log with timestamps jittered by ± `jitter_ms` (ms, 1 ns resolution),
/// position in mm, force in mN, renamed and quoted columns, `;` delimiter, and imports it at
/// 1 kHz.
fn downsample(jitter_ms: f64) -> Downsampled {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("robot_log.csv");
    let mut rng = capture::rng::SplitMix64::new(0x9e37_79b9_7f4a_7c15);
    // 20 006 samples span 2.0005 s, so the 1 kHz grid ends at t0 + 2 s whatever the jitter.
    let times_ms: Vec<String> = (0..20_006)
        .map(|i| {
            format!(
                "{:.6}",
                12.5 + 0.1 * i as f64 + jitter_ms * (2.0 * rng.next_f64() - 1.0)
            )
        })
        .collect();
    let t0: f64 = times_ms[0].parse::<f64>().unwrap() / 1000.0;
    let mut csv = String::from("# logged by rig-7, 10 kHz\n\"Time\";\"X pos\";\"Fz\";\"status\"\n");
    for t_ms in &times_ms {
        // The importer reads `t_ms / 1000`; the signals are evaluated at that same instant.
        let t = t_ms.parse::<f64>().unwrap() / 1000.0;
        let x_mm = (position_lf(t) + POS_HF_M * hf(t, t0)) * 1e3;
        let f_mn = (force_lf(t) + FORCE_HF_N * hf(t, t0)) * 1e3;
        writeln!(csv, "{t_ms};{x_mm};{f_mn};ok").unwrap();
    }
    std::fs::write(&input, csv).unwrap();
    let out = dir.path().join("imported.csv");
    let t = text(&success(import(
        &input,
        &out,
        &[
            "--map",
            "time_s=Time[ms], tangential_position_m=X pos[mm], normal_force_n=Fz[mN]",
            "--rate-hz",
            "1000",
            "--meta",
            "surface=sandpaper_400",
        ],
    )));
    assert!(
        t.contains("imported 20006 rows") && t.contains("2001 rows at 1000 Hz"),
        "{t}"
    );
    assert!(t.contains("low-pass at 400 Hz"), "{t}");

    let c = Capture::read_file(&out, CaptureKind::Rubbing).unwrap();
    assert_eq!(c.len(), 2001);
    assert_eq!(c.time()[0], t0);
    assert!((c.time()[2000] - (t0 + 2.0)).abs() < 1e-12);
    let m = c.metadata();
    assert_eq!((m.device(), m.rate_hz()), ("imported", 1000.0));
    assert_eq!(m.get("source"), Some("robot_log.csv"));
    assert_eq!(
        m.get("map"),
        Some("time_s=Time[ms],tangential_position_m=Xpos[mm],normal_force_n=Fz[mN]")
    );
    let source_rate: f64 = m.get("source_rate_hz").unwrap().parse().unwrap();
    assert!((source_rate - 10_000.0).abs() < 0.1, "{source_rate}");
    assert_eq!(m.get("surface"), Some("sandpaper_400"));

    // Away from the ends (50 ms: the filter's edge effects), the residual is what is left of
    // the vibration plus the error on the slow signals.
    let pos_error_m = max_error(&c, "tangential_position_m", position_lf, 0.05);
    let force_error_n = max_error(&c, "normal_force_n", force_lf, 0.05);
    let d = Downsampled {
        pos_error_m,
        force_error_n,
        pos_residual: pos_error_m / POS_HF_M,
        force_residual: force_error_n / FORCE_HF_N,
        pos_edge_residuals: [0.0, 0.005, 0.01, 0.02]
            .map(|margin| max_error(&c, "tangential_position_m", position_lf, margin) / POS_HF_M),
    };
    println!(
        "10 kHz ± {jitter_ms} ms -> 1 kHz: position error {:.3e} m ({:.2e} of amplitude, {:.2e} of \
         the 2 kHz amplitude), force error {:.3e} N ({:.2e}, {:.2e}); position residual within \
         0/5/10/20 ms of the ends {}",
        d.pos_error_m,
        d.pos_error_m / POS_AMPLITUDE_M,
        d.pos_residual,
        d.force_error_n,
        d.force_error_n / FORCE_AMPLITUDE_N,
        d.force_residual,
        d.pos_edge_residuals.map(|r| format!("{r:.2e}")).join("/")
    );
    d
}

/// A 2 kHz vibration in a 10 kHz log would alias to a constant offset of its full
/// amplitude on a 1 kHz grid (the signals are phased for that worst case). The
/// anti-aliasing filter removes it while the slow signals come through.
#[test]
fn downsampling_removes_what_would_alias_and_keeps_the_signal() {
    // Uniform log: the filter alone. Its forward-backward gain at 2 kHz on the 10 kHz grid,
    // from the bilinear Butterworth design, is 1 / (1 + (tan(π·0.2) / tan(π·0.04))^8).
    let ratio = (PI * HF_HZ / 10_000.0).tan() / (PI * 400.0 / 10_000.0).tan();
    let filter_gain = 1.0 / (1.0 + ratio.powi(8));
    let d = downsample(0.0);
    println!("filter gain at 2 kHz (forward-backward): {filter_gain:.3e}");
    assert!(
        d.pos_residual < 2.0 * filter_gain,
        "{} vs {filter_gain}",
        d.pos_residual
    );
    assert!(
        d.force_residual < 2.0 * filter_gain,
        "{} vs {filter_gain}",
        d.force_residual
    );
    assert!(d.pos_error_m < 1e-6 * POS_AMPLITUDE_M, "{}", d.pos_error_m);
    assert!(d.force_error_n < 1e-5 * FORCE_AMPLITUDE_N, "{}", d.force_error_n);
    edges_settle(&d);

    // ±2 µs timestamp jitter: interpolating the vibration between jittered samples turns
    // part of it into broadband noise. Its peak before filtering is at most
    // ω² · δ · h / 2 of the amplitude (linear interpolation error at offset δ ≤ 2 µs in an
    // interval h = 100 µs, 1.6 %); the in-band part that survives is well below that.
    let before_filter = (2.0 * PI * HF_HZ).powi(2) * 2e-6 * 1e-4 / 2.0;
    let d = downsample(0.002);
    println!("jitter bound before filtering: {before_filter:.3e}");
    assert!(d.pos_residual < before_filter / 2.0, "{}", d.pos_residual);
    assert!(d.force_residual < before_filter / 2.0, "{}", d.force_residual);
    assert!(d.pos_residual < 1e-2 && d.force_residual < 1e-2);
    edges_settle(&d);
}

/// The filter pads each end with the odd reflection about the end sample, so the vibration's
/// value at that sample leaks into the first and last milliseconds (here its full amplitude:
/// the end sample is a peak) and dies out within a few cut-off periods (2.5 ms each).
fn edges_settle(d: &Downsampled) {
    let [at_ends, after_5ms, after_10ms, after_20ms] = d.pos_edge_residuals;
    let floor = d.pos_residual;
    assert!(at_ends <= 1.0 + 1e-6, "{at_ends}");
    assert!(after_5ms < 1e-2, "{after_5ms}");
    assert!(after_10ms < (2.0 * floor).max(1e-4), "{after_10ms}");
    assert!(after_20ms <= 2.0 * floor, "{after_20ms}");
}

/// A 100 Hz log upsampled to 1 kHz: linear interpolation, so the error is bounded by
/// `h² / 8 · max|x''|` and, as the grid hits the midpoints near the peaks, nearly reaches it.
#[test]
fn upsampling_interpolates_linearly_within_the_computed_bound() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("slow.csv");
    let h = 0.01;
    let mut csv = String::from("t,x_um,force\n");
    for i in 0..=300 {
        let t = i as f64 * h;
        // Positions in µm; the importer divides by 1e6, so the reference does too.
        writeln!(csv, "{t},{},{}", position_lf(t) * 1e6, force_lf(t)).unwrap();
    }
    std::fs::write(&input, csv).unwrap();
    let out = dir.path().join("fast.csv");
    let t = text(&success(import(
        &input,
        &out,
        &[
            "--map",
            "time_s=t,tangential_position_m=x_um[µm],normal_force_n=force",
            "--rate-hz",
            "1000",
        ],
    )));
    assert!(t.contains("linear interpolation"), "{t}");
    let c = Capture::read_file(&out, CaptureKind::Rubbing).unwrap();
    assert_eq!(c.len(), 3001);
    assert_eq!(
        c.metadata().get("map"),
        Some("time_s=t,tangential_position_m=x_um[um],normal_force_n=force")
    );

    let pos_bound = h * h / 8.0 * POS_AMPLITUDE_M * (2.0 * PI * 3.0).powi(2);
    let force_bound = h * h / 8.0 * FORCE_AMPLITUDE_N * (2.0 * PI * 7.0).powi(2);
    let pos_error = max_error(&c, "tangential_position_m", position_lf, 0.0);
    let force_error = max_error(&c, "normal_force_n", force_lf, 0.0);
    println!(
        "100 Hz -> 1 kHz: position error {pos_error:.4e} m (bound {pos_bound:.4e}), force error \
         {force_error:.4e} N (bound {force_bound:.4e})"
    );
    // Rounding in the µm round trip is ~1e-18 m, far below the bound's slack.
    assert!(pos_error <= pos_bound * (1.0 + 1e-9), "{pos_error} > {pos_bound}");
    assert!(
        force_error <= force_bound * (1.0 + 1e-9),
        "{force_error} > {force_bound}"
    );
    assert!(pos_error > 0.9 * pos_bound, "{pos_error} vs {pos_bound}");
    assert!(force_error > 0.9 * force_bound, "{force_error} vs {force_bound}");
    // At the input's own samples the output is the input.
    let x = c.column("tangential_position_m").unwrap();
    for k in (0..c.len()).step_by(10) {
        let expected = position_lf(k as f64 / 1000.0);
        assert!((x[k] - expected).abs() <= 1e-15, "{k}: {} vs {expected}", x[k]);
    }
}

/// A simulator capture rewritten with other names and units, imported at its own rate,
/// comes back value for value.
#[test]
fn a_capture_in_other_units_passes_through_unchanged() {
    let dir = tempfile::tempdir().unwrap();
    let original = dir.path().join("x.csv");
    succeeds(&[
        "capture",
        "--device",
        "sim",
        "--protocol",
        "rubbing",
        "--surface",
        "sandpaper_400",
        "--unpaced",
        "--quiet",
        "--out",
        original.to_str().unwrap(),
    ]);
    let capture = Capture::read_file(&original, CaptureKind::Rubbing).unwrap();
    // (capture column, log name, log unit, factor from SI to the log's unit)
    let renames: [(&str, &str, &str, f64); 7] = [
        ("time_s", "Time (ms)", "ms", 1e3),
        ("tangential_position_m", "x", "mm", 1e3),
        ("tangential_velocity_mps", "vx", "mm/s", 1e3),
        ("commanded_velocity_mps", "vx_cmd", "m/s", 1.0),
        ("normal_position_m", "z", "um", 1e6),
        ("normal_force_n", "Fz", "mN", 1e3),
        ("friction_force_n", "Ft", "N", 1.0),
    ];
    assert_eq!(capture.columns(), renames.map(|r| r.0));
    let mut csv = String::from("# exported for the lab\n");
    let header: Vec<String> = renames.iter().rev().map(|r| format!("\"{}\"", r.1)).collect();
    writeln!(csv, "{}\tunused", header.join("\t")).unwrap();
    for i in 0..capture.len() {
        let row: Vec<String> = renames
            .iter()
            .rev()
            .map(|r| (capture.column(r.0).unwrap()[i] * r.3).to_string())
            .collect();
        writeln!(csv, "{}\tn/a", row.join("\t")).unwrap();
    }
    let input = dir.path().join("lab export.tsv");
    std::fs::write(&input, csv).unwrap();
    let map: Vec<String> = renames
        .iter()
        .map(|r| format!("{}={}[{}]", r.0, r.1, r.2))
        .collect();
    let map = map.join(",");
    for rate in [None, Some("1000")] {
        let out = dir.path().join("back.csv");
        let mut args = vec!["--map", map.as_str(), "--meta", "surface=sandpaper_400"];
        if let Some(rate) = rate {
            args.extend(["--rate-hz", rate]);
        }
        let t = text(&success(import(&input, &out, &args)));
        assert!(t.contains("(passed through)"), "{t}");
        let back = Capture::read_file(&out, CaptureKind::Rubbing).unwrap();
        assert_eq!(back.columns(), capture.columns());
        assert_eq!(back.len(), capture.len());
        let mut worst: f64 = 0.0;
        for (name, (a, b)) in capture
            .columns()
            .iter()
            .zip(capture.data().iter().zip(back.data()))
        {
            for (i, (&x, &y)) in a.iter().zip(b).enumerate() {
                let relative = (x - y).abs() / x.abs().max(y.abs()).max(f64::MIN_POSITIVE);
                assert!(x == y || relative <= 1e-12, "{name}[{i}]: {x} vs {y}");
                worst = worst.max(if x == y { 0.0 } else { relative });
            }
        }
        println!("pass-through: largest relative difference {worst:.2e}");
        let m = back.metadata();
        assert_eq!(m.rate_hz(), 1000.0);
        assert_eq!(m.get("source"), Some("lab_export.tsv"));
        assert_eq!(m.get("source_rate_hz"), Some("1000"));
        assert_eq!(m.get("surface"), Some("sandpaper_400"));
    }
}

/// Mistakes in the map or the log are errors that say where, and leave no output behind.
#[test]
fn errors_name_the_problem_and_leave_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("log.csv");
    let out = dir.path().join("out.csv");
    let good = "t,x,Fz\n0,1,0.3\n0.001,2,0.3\n0.002,3,0.3\n";
    let cases: [(&str, &str, &[&str]); 5] = [
        (
            good,
            "time_s=t,tangential_position_m=pos,normal_force_n=Fz",
            &[
                "no column `pos`",
                "its columns: t, x, Fz",
                "tangential_position_m=pos",
            ],
        ),
        (
            good,
            "time_s=t,tangential_position_m=x",
            &["a rubbing capture needs `normal_force_n`", "log.csv"],
        ),
        (
            "t,x,Fz\n0,1,0.3\n0.001,2,0.3x\n0.002,3,0.3\n",
            "time_s=t,tangential_position_m=x,normal_force_n=Fz",
            &["log.csv:3: column `Fz`: `0.3x` is not a number"],
        ),
        (
            "t,x,Fz\n0,1,0.3\n0.002,2,0.3\n0.001,3,0.3\n",
            "time_s=t,tangential_position_m=x,normal_force_n=Fz",
            &["log.csv:4: column `t`: time 0.001 s is not after the previous row's 0.002 s"],
        ),
        (
            good,
            "time_s=t[h],tangential_position_m=x,normal_force_n=Fz",
            &["--map entry `time_s=t[h]`: unknown unit `h`"],
        ),
    ];
    for (content, map, needles) in cases {
        std::fs::write(&input, content).unwrap();
        let o = import(&input, &out, &["--map", map]);
        let t = text(&o);
        assert!(!o.status.success(), "{t}");
        assert!(t.starts_with("error: "), "{t}");
        for needle in needles {
            assert!(t.contains(needle), "`{needle}` missing from:\n{t}");
        }
        assert!(!out.exists(), "{map}: output left behind");
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(left.len(), 1, "only the input remains: {left:?}");
    }
    let o = palpus(&["import", "--help"]);
    let t = text(&o);
    for needle in [
        "--map",
        "--rate-hz",
        "--input-rate-hz",
        "--meta",
        "low-pass",
        "mm/s",
        "--max-upsample",
        "--drop-implausible",
        "100 kHz",
    ] {
        assert!(t.contains(needle), "`{needle}` missing from:\n{t}");
    }
}

/// A few bytes of input cannot ask for gigabytes: the output's size is checked against a
/// budget before anything is allocated, and the error says which numbers and which option.
#[test]
fn small_inputs_cannot_ask_for_huge_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("log.csv");
    let out = dir.path().join("out.csv");
    let map = "time_s=t,tangential_position_m=x,normal_force_n=Fz";
    let fails_with = |content: &str, args: &[&str], needles: &[&str]| {
        std::fs::write(&input, content).unwrap();
        let mut all = vec!["--map", map];
        all.extend_from_slice(args);
        let o = import(&input, &out, &all);
        let t = text(&o);
        assert!(!o.status.success(), "{t}");
        for needle in needles {
            assert!(t.contains(needle), "`{needle}` missing from:\n{t}");
        }
        assert!(!out.exists(), "output left behind: {t}");
    };
    // 2 rows spanning 10⁵ s at 1 kHz would be 10⁸ rows.
    fails_with(
        "t,x,Fz\n0,0.001,0.3\n100000,0.002,0.3\n",
        &["--rate-hz", "1000"],
        &[
            "log.csv: the output would have 100000001 rows",
            "from 2 input rows, more than 2000",
            "--max-upsample",
        ],
    );
    // However large the factor, an output bigger than its input stops at 10⁷ rows.
    fails_with(
        "t,x,Fz\n0,0.001,0.3\n100000,0.002,0.3\n",
        &["--rate-hz", "1000", "--max-upsample", "1e12"],
        &["more than 10000000"],
    );
    // A rate far beyond any rig (a time unit off by 10⁴ or more).
    let six_seconds: String = std::iter::once("t,x,Fz\n".to_owned())
        .chain((0..=6).map(|i| format!("{i},0.001,0.3\n")))
        .collect();
    fails_with(
        &six_seconds,
        &["--rate-hz", "3e7"],
        &["log.csv: --rate-hz 30000000: must be from 1 to 100000 Hz"],
    );
}

/// One garbage value must not become a garbage capture: it is an error naming where it is,
/// or, with --drop-implausible, a dropped row that leaves the rest as it would be.
#[test]
fn implausible_values_are_refused_or_dropped() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("log.csv");
    let out = dir.path().join("out.csv");
    let mut csv = String::from("t,x,Fz,Fx\n");
    for i in 0..600 {
        let t = i as f64 * 1e-3;
        let fx = if i == 300 {
            "1e308".to_owned()
        } else {
            format!("{}", 0.1 + 0.01 * (7.0 * t).sin())
        };
        writeln!(csv, "{t},{},{},{fx}", position_lf(t), force_lf(t)).unwrap();
    }
    std::fs::write(&input, csv).unwrap();
    let map = "time_s=t,tangential_position_m=x,normal_force_n=Fz,friction_force_n=Fx";
    let o = import(&input, &out, &["--map", map, "--rate-hz", "100"]);
    let t = text(&o);
    assert!(!o.status.success(), "{t}");
    assert!(
        t.contains("log.csv:302: column `Fx`: `1e308` is 1e308 in SI units, outside ±1e6"),
        "{t}"
    );
    assert!(t.contains("--drop-implausible"), "{t}");
    assert!(!out.exists());

    let t = text(&success(import(
        &input,
        &out,
        &["--map", map, "--rate-hz", "100", "--drop-implausible"],
    )));
    assert!(
        t.contains("imported 599 rows") && t.contains("dropped 1 row(s)"),
        "{t}"
    );
    let c = Capture::read_file(&out, CaptureKind::Rubbing).unwrap();
    let friction = c.column("friction_force_n").unwrap();
    assert!(friction.iter().all(|f| (0.08..0.12).contains(f)), "{friction:?}");

    // A capture file holding such a value is refused where it is, too.
    let capture_text = std::fs::read_to_string(&out).unwrap();
    let mut lines: Vec<String> = capture_text.lines().map(str::to_owned).collect();
    let fields: Vec<&str> = lines[4].split(',').collect();
    let last = fields.len() - 1;
    let mut fields: Vec<String> = fields.iter().map(|f| (*f).to_owned()).collect();
    fields[last] = "-1e300".into();
    lines[4] = fields.join(",");
    std::fs::write(&out, lines.join("\n") + "\n").unwrap();
    let e = Capture::read_file(&out, CaptureKind::Rubbing).unwrap_err();
    assert_eq!(
        (e.line, e.column.as_deref()),
        (Some(5), Some("friction_force_n")),
        "{e}"
    );
    assert!(e.to_string().contains("-1e300 is outside ±1e6"), "{e}");
}

/// A committed input shaped like a public dataset's quirk (`tests/fixtures/import/`).
fn fixture(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/import")
        .join(name)
}

#[test]
fn a_header_less_file_is_read_by_index_or_by_given_names() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.csv");
    let input = fixture("headerless.csv");

    // Read as if its first row named the columns, the file gets told what it looks like.
    let o = import(
        &input,
        &out,
        &["--map", "time_s=t,tangential_position_m=x,normal_force_n=Fz"],
    );
    let t = text(&o);
    assert!(!o.status.success(), "{t}");
    assert!(t.contains("headerless.csv:1:"), "{t}");
    assert!(
        t.contains("looks like data") && t.contains("--no-header") && t.contains("--columns"),
        "{t}"
    );
    assert!(!out.exists());

    let cases: [&[&str]; 2] = [
        &[
            "--no-header",
            "--map",
            "time_s=0,tangential_position_m=1,normal_force_n=2",
        ],
        &[
            "--columns",
            "t,x,Fz",
            "--map",
            "time_s=t,tangential_position_m=x,normal_force_n=Fz",
        ],
    ];
    for args in cases {
        let t = text(&success(import(&input, &out, args)));
        assert!(t.contains("imported 5 rows"), "{args:?}: {t}");
        let c = Capture::read_file(&out, CaptureKind::Rubbing).unwrap();
        assert_eq!(c.time(), &[0.0, 0.001, 0.002, 0.003, 0.004], "{args:?}");
        assert_eq!(
            c.column("normal_force_n").unwrap(),
            &[0.3, 0.302, 0.304, 0.306, 0.308],
            "{args:?}"
        );
    }

    // Names for fewer columns than the file has are an error at the first row.
    let o = import(
        &input,
        &out,
        &[
            "--columns",
            "t,x",
            "--map",
            "time_s=t,tangential_position_m=x,normal_force_n=x",
        ],
    );
    let t = text(&o);
    assert!(!o.status.success(), "{t}");
    assert!(
        t.contains(
            "headerless.csv:1: column `field 3 (after the last named column)`: --columns \
             names 2 columns, but this row has 3 fields"
        ),
        "{t}"
    );
}

#[test]
fn repeated_timestamps_are_refused_merged_or_dropped() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.csv");
    let input = fixture("repeated_time.csv");
    let map = "time_s=t[ms],tangential_position_m=x[mm],normal_force_n=Fz";

    let o = import(&input, &out, &["--map", map]);
    let t = text(&o);
    assert!(!o.status.success(), "{t}");
    assert!(
        t.contains("repeated_time.csv:4: column `t`: time 0.001 s is not after"),
        "{t}"
    );
    assert!(!out.exists());

    let close =
        |a: &[f64], b: &[f64]| a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12);
    let t = text(&success(import(
        &input,
        &out,
        &["--map", map, "--repeated-time", "mean"],
    )));
    assert!(
        t.contains("imported 5 rows") && t.contains("3 row(s) repeating the previous row's time merged"),
        "{t}"
    );
    let c = Capture::read_file(&out, CaptureKind::Rubbing).unwrap();
    assert_eq!(c.time(), &[0.0, 0.001, 0.002, 0.003, 0.004]);
    let x = c.column("tangential_position_m").unwrap();
    assert!(close(x, &[1.0e-3, 1.2e-3, 1.2e-3, 1.5e-3, 1.4e-3]), "{x:?}");
    let fz = c.column("normal_force_n").unwrap();
    assert!(close(fz, &[0.30, 0.32, 0.32, 0.35, 0.34]), "{fz:?}");

    let t = text(&success(import(
        &input,
        &out,
        &["--map", map, "--repeated-time", "drop"],
    )));
    assert!(
        t.contains("imported 5 rows") && t.contains("3 row(s) repeating the previous row's time dropped"),
        "{t}"
    );
    let c = Capture::read_file(&out, CaptureKind::Rubbing).unwrap();
    assert_eq!(
        c.column("normal_force_n").unwrap(),
        &[0.30, 0.31, 0.32, 0.33, 0.34]
    );
}

#[test]
fn a_delimiter_ending_every_line_is_ignored_but_a_value_there_is_not() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.csv");
    let map = "time_s=t[ms],tangential_position_m=x[mm],normal_force_n=Fz";

    let t = text(&success(import(
        &fixture("trailing_delimiter.csv"),
        &out,
        &["--map", map],
    )));
    assert!(t.contains("imported 4 rows"), "{t}");
    let c = Capture::read_file(&out, CaptureKind::Rubbing).unwrap();
    assert_eq!(c.column("normal_force_n").unwrap(), &[0.30, 0.31, 0.32, 0.33]);

    let o = import(&fixture("trailing_value.csv"), &out, &["--map", map]);
    let t = text(&o);
    assert!(!o.status.success(), "{t}");
    assert!(
        t.contains(
            "trailing_value.csv:3: column `field 4 (after the last named column)`: expected 3 \
             fields like the header, found 4"
        ),
        "{t}"
    );
}

/// Sensor dropouts written as `nan`/`inf`: refused by default, skipped or bridged on request,
/// and the import says how many.
#[test]
fn non_finite_cells_are_refused_dropped_or_bridged() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.csv");
    let input = fixture("non_finite.csv");
    let map = "time_s=t_ms[ms],tangential_position_m=x_mm[mm],normal_force_n=Fz_N,friction_force_n=Fx_N";

    let o = import(&input, &out, &["--map", map, "--rate-hz", "1000"]);
    let t = text(&o);
    assert!(!o.status.success(), "{t}");
    assert!(
        t.contains("non_finite.csv:6: column `Fz_N`: `nan` is not finite") && t.contains("--non-finite"),
        "{t}"
    );
    assert!(!out.exists());

    let t = text(&success(import(
        &input,
        &out,
        &["--map", map, "--rate-hz", "1000", "--non-finite", "drop"],
    )));
    assert!(
        t.contains("imported 9 rows") && t.contains("dropped 3 row(s) with a non-finite value"),
        "{t}"
    );

    let t = text(&success(import(
        &input,
        &out,
        &["--map", map, "--rate-hz", "1000", "--non-finite", "bridge"],
    )));
    assert!(
        t.contains("imported 12 rows") && t.contains("bridged 3 non-finite cell(s)"),
        "{t}"
    );
    let c = Capture::read_file(&out, CaptureKind::Rubbing).unwrap();
    // The fixture's columns are straight lines, so the bridge restores them exactly.
    let fz = c.column("normal_force_n").unwrap();
    let fx = c.column("friction_force_n").unwrap();
    for i in 0..12 {
        assert!((fz[i] - (0.30 + 0.01 * i as f64)).abs() < 1e-9, "{fz:?}");
        assert!((fx[i] - (0.10 + 0.005 * i as f64)).abs() < 1e-9, "{fx:?}");
    }

    // --drop-implausible alone still skips non-finite rows; --non-finite overrides it.
    let t = text(&success(import(
        &input,
        &out,
        &["--map", map, "--rate-hz", "1000", "--drop-implausible"],
    )));
    assert!(t.contains("dropped 3 row(s) with a non-finite value"), "{t}");
    let t = text(&success(import(
        &input,
        &out,
        &[
            "--map",
            map,
            "--rate-hz",
            "1000",
            "--drop-implausible",
            "--non-finite",
            "bridge",
        ],
    )));
    assert!(t.contains("bridged 3") && !t.contains("dropped"), "{t}");

    let o = import(
        &input,
        &out,
        &["--map", map, "--rate-hz", "1000", "--non-finite", "zero"],
    );
    assert!(!o.status.success());
    assert!(
        text(&o).contains("expected drop, bridge or error"),
        "{}",
        text(&o)
    );
}

/// Two logs of the same nominal rate whose clocks err to either side of it are resampled the
/// same way: interpolated, not one interpolated and the other low-passed.
#[test]
fn logs_of_the_same_nominal_rate_take_the_same_path() {
    let dir = tempfile::tempdir().unwrap();
    let map = "time_s=t_s,tangential_position_m=x_m,normal_force_n=Fz_N";
    let mut forces = Vec::new();
    for name in ["rate_2199_8hz.csv", "rate_2200_1hz.csv"] {
        let out = dir.path().join(name);
        let t = text(&success(import(
            &fixture(name),
            &out,
            &["--map", map, "--rate-hz", "2200"],
        )));
        assert!(
            t.contains("at 2200 Hz") && t.contains("(linear interpolation)") && !t.contains("low-pass"),
            "{name}: {t}"
        );
        let c = Capture::read_file(&out, CaptureKind::Rubbing).unwrap();
        forces.push(c.column("normal_force_n").unwrap().to_vec());
    }
    let n = forces[0].len().min(forces[1].len());
    assert!(n >= 118, "{n}");
    // A 100 Hz, 0.05 N sine on grids 0.014 % apart: the same samples to well within 1e-3 N.
    let worst = forces[0][..n]
        .iter()
        .zip(&forces[1][..n])
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    println!("2199.8 Hz vs 2200.1 Hz log at 2200 Hz: largest difference {worst:.2e} N");
    assert!(worst < 1e-3, "{worst}");
    let o = palpus(&["import", "--help"]);
    assert!(text(&o).contains("1.01"), "{}", text(&o));
}

/// A force-depth curve digitized from a figure has no time: it comes from the depth at the
/// insertion speed, and the curve is resampled like any log.
#[test]
fn time_is_derived_from_position_at_a_known_speed() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.csv");
    let run = |input: &Path, speed: &str| {
        palpus(&[
            "import",
            input.to_str().unwrap(),
            "--kind",
            "insertion",
            "--out",
            out.to_str().unwrap(),
            "--map",
            "depth_m=depth_mm[mm],axial_force_n=force_N",
            "--time-from-position",
            "depth_mm[mm]",
            "--speed-mps",
            speed,
            "--rate-hz",
            "100",
        ])
    };
    let t = text(&success(run(&fixture("force_depth_digitized.csv"), "0.005")));
    assert!(t.contains("imported 30 rows"), "{t}");
    let c = Capture::read_file(&out, CaptureKind::Insertion).unwrap();
    // 11.5 mm at 5 mm/s: 2.3 s, 231 samples 0.05 mm apart.
    assert_eq!(c.len(), 231);
    let depth = c.column("depth_m").unwrap();
    for (k, d) in depth.iter().enumerate() {
        assert!((d - k as f64 * 5e-5).abs() < 1e-9, "{k}: {d}");
    }
    let force = c.column("axial_force_n").unwrap();
    assert!((force[120] - 0.72).abs() < 1e-9, "{}", force[120]);
    assert_eq!(c.metadata().get("time_from"), Some("depth_mm[mm]@0.005mps"));

    // Against the stroke: the line where the depth goes back is named.
    let back = dir.path().join("back.csv");
    std::fs::write(&back, "depth_mm,force_N\n0,0\n1,0.1\n0.9,0.2\n2,0.3\n").unwrap();
    let o = run(&back, "0.005");
    let t = text(&o);
    assert!(!o.status.success(), "{t}");
    assert!(
        t.contains("back.csv:4: column `depth_mm`: position 0.0009 m does not advance"),
        "{t}"
    );
    // A negative speed is a withdrawal: the same file read backwards fails at its first row.
    let o = run(&fixture("force_depth_digitized.csv"), "-0.005");
    assert!(text(&o).contains("force_depth_digitized.csv:4:"), "{}", text(&o));
    // The unit is required.
    let o = palpus(&[
        "import",
        "x.csv",
        "--kind",
        "insertion",
        "--out",
        out.to_str().unwrap(),
        "--map",
        "depth_m=depth_mm[mm],axial_force_n=force_N",
        "--time-from-position",
        "depth_mm",
        "--speed-mps",
        "0.005",
    ]);
    assert!(text(&o).contains("unit in brackets"), "{}", text(&o));
    let help = text(&palpus(&["import", "--help"]));
    for needle in ["--time-from-position", "--speed-mps", "--non-finite"] {
        assert!(help.contains(needle), "`{needle}` missing from:\n{help}");
    }
}

#[test]
fn packed_rows_are_unrolled_into_consecutive_samples() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.csv");
    let input = fixture("packed_rows.csv");
    let map = "time_s=time_ms[ms],tangential_position_m=x_mm[mm],normal_force_n=force_n,\
               accel_x_mps2=acc";

    // 8 rows at 100 Hz, ten accelerometer samples each: 80 samples 1 ms apart, a uniform
    // 1 kHz timeline that is passed through.
    let t = text(&success(import(
        &input,
        &out,
        &["--map", map, "--unroll", "acc=acc_0..acc_9", "--rate-hz", "1000"],
    )));
    assert!(
        t.contains("imported 80 rows") && t.contains("passed through"),
        "{t}"
    );
    let c = Capture::read_file(&out, CaptureKind::Rubbing).unwrap();
    assert_eq!(c.len(), 80);
    let acc = c.column("accel_x_mps2").unwrap();
    let force = c.column("normal_force_n").unwrap();
    for (j, (&t, (&a, &f))) in c.time().iter().zip(acc.iter().zip(force)).enumerate() {
        assert!((t - j as f64 * 1e-3).abs() < 1e-9, "sample {j} at {t} s");
        // Row i, column acc_k holds i * 10 + k: the sample's index.
        assert!((a - j as f64).abs() < 1e-9, "sample {j}: {a}");
        // The force rises 0.5 N a row: interpolated, 0.05 N a sample; the last row holds.
        let expected = if j < 70 { 0.05 * j as f64 } else { 3.5 };
        assert!(
            (f - expected).abs() < 1e-9,
            "sample {j}: {f} N, expected {expected}"
        );
    }

    // Held, the force is a staircase.
    success(import(
        &input,
        &out,
        &[
            "--map",
            map,
            "--unroll",
            "acc=acc_0..acc_9",
            "--unroll-slow",
            "hold",
            "--rate-hz",
            "1000",
        ],
    ));
    let c = Capture::read_file(&out, CaptureKind::Rubbing).unwrap();
    let force = c.column("normal_force_n").unwrap();
    assert!(
        force
            .iter()
            .enumerate()
            .all(|(j, &f)| (f - 0.5 * (j / 10) as f64).abs() < 1e-12),
        "{force:?}"
    );

    // A range that leaves out a packed column, and one that names a column the file lacks.
    for (range, says) in [
        ("acc=acc_0..acc_8", "column `acc_9`, next to the range"),
        ("acc=acc_0..acc_10", "`acc_10`"),
    ] {
        let o = import(
            &input,
            &out,
            &["--map", map, "--unroll", range, "--rate-hz", "1000"],
        );
        let t = text(&o);
        assert!(!o.status.success(), "{range}: {t}");
        assert!(t.contains("packed_rows.csv") && t.contains(says), "{range}: {t}");
    }
}

// The signals `tests/fixtures/import/multistream_make.py` sampled on each file's own clock.
const G_MPS2: f64 = 9.80665;

fn multistream_fz_n(t: f64) -> f64 {
    2.0 + 0.5 * (2.0 * PI * 0.7 * t).sin()
}

fn multistream_fx_n(t: f64) -> f64 {
    0.6 + 0.2 * (2.0 * PI * 0.5 * t).cos()
}

fn multistream_x_m(t: f64) -> f64 {
    0.020 * (2.0 * PI * 0.4 * t).sin()
}

fn multistream_acc_mps2(t: f64) -> f64 {
    0.3 * G_MPS2 * (2.0 * PI * 40.0 * t).sin()
}

/// A signal of time, s, in SI units.
type Signal = fn(f64) -> f64;

/// Linear interpolation's error bound `h² / 8 · max|x''|` for `amplitude · sin(2π f t)`
/// sampled every `h` seconds at most, plus the fixtures' 1e-9 rounding of values.
fn interpolation_bound(h_s: f64, amplitude: f64, freq_hz: f64) -> f64 {
    h_s * h_s / 8.0 * amplitude * (2.0 * PI * freq_hz).powi(2) + 1e-9
}

const MULTISTREAM_MAP: &str = "time_s=t[ms],normal_force_n=Fz,friction_force_n=Fx,\
                               tangential_position_m=x[mm],accel_x_mps2=acc[g]";

/// `palpus import` of the three multistream fixtures (force, position, packed vibration).
fn import_multistream(out: &Path, map: &str, args: &[&str]) -> std::process::Output {
    let unroll = ["--unroll", "acc=acc_0..acc_21"];
    import_multistream_with(out, map, &[&unroll[..], args].concat())
}

/// [`import_multistream`] without its `--unroll`: `args` say everything else.
fn import_multistream_with(out: &Path, map: &str, args: &[&str]) -> std::process::Output {
    let (force, position, vib) = (
        fixture("multistream_force.csv"),
        fixture("multistream_position.csv"),
        fixture("multistream_vib_packed.csv"),
    );
    let mut all = vec![
        "import",
        force.to_str().unwrap(),
        position.to_str().unwrap(),
        vib.to_str().unwrap(),
        "--kind",
        "rubbing",
        "--rate-hz",
        "1000",
        "--map",
        map,
        "--out",
        out.to_str().unwrap(),
    ];
    all.extend_from_slice(args);
    palpus(&all)
}

#[test]
fn streams_on_separate_clocks_are_joined_onto_one_grid() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("trial.csv");
    let o = success(import_multistream(
        &out,
        MULTISTREAM_MAP,
        &["--repeated-time", "mean"],
    ));
    let said = text(&o);
    for name in [
        "multistream_force.csv",
        "multistream_position.csv",
        "multistream_vib_packed.csv",
    ] {
        assert!(said.contains(name), "{said}");
    }
    assert!(
        said.contains("joined 3 inputs") && said.contains("cut 0.041700 s before"),
        "{said}"
    );
    let c = Capture::read_file(&out, CaptureKind::Rubbing).unwrap();
    assert_eq!(
        c.columns(),
        &[
            "time_s",
            "normal_force_n",
            "friction_force_n",
            "tangential_position_m",
            "accel_x_mps2"
        ]
    );
    // The overlap starts at the position log's first time (41.7 ms) and ends by the earliest
    // last time: the vibration's last unrolled sample, 2943.3 ms + 21/22 of 10 ms.
    let time = c.time();
    assert!((time[0] - 0.0417).abs() < 1e-12, "{}", time[0]);
    let last_vib_s = 2.9433 + 0.010 * 21.0 / 22.0;
    assert!(time[time.len() - 1] <= last_vib_s + 1e-9 && time[time.len() - 1] > last_vib_s - 0.001);
    for (k, pair) in time.windows(2).enumerate() {
        assert!((pair[1] - pair[0] - 0.001).abs() < 1e-9, "interval {k}: {pair:?}");
    }
    // Each column against its signal, within the interpolation error of its own clock (the
    // generator's longest intervals: 1.25/88 s for forces, 1.3/88.5 s for position; the
    // vibration is interpolated at 2.2 kHz after a low-pass that leaves 40 Hz alone).
    let checks: [(&str, Signal, f64); 4] = [
        (
            "normal_force_n",
            multistream_fz_n,
            interpolation_bound(1.25 / 88.0, 0.5, 0.7),
        ),
        (
            "friction_force_n",
            multistream_fx_n,
            interpolation_bound(1.25 / 88.0, 0.2, 0.5),
        ),
        (
            "tangential_position_m",
            multistream_x_m,
            interpolation_bound(1.3 / 88.5, 0.020, 0.4),
        ),
        (
            "accel_x_mps2",
            multistream_acc_mps2,
            interpolation_bound(1.0 / 2200.0, 0.3 * G_MPS2, 40.0),
        ),
    ];
    for (column, signal, bound) in checks {
        let values = c.column(column).unwrap();
        let error = time
            .iter()
            .zip(values)
            .map(|(&t, &v)| (v - signal(t)).abs())
            .fold(0.0, f64::max);
        println!("{column}: max error {error:.3e} (bound {bound:.3e})");
        assert!(error <= bound, "{column}: max error {error} > bound {bound}");
    }
    // Every input is recorded with its hash, its part of the map and its own rate.
    let m = c.metadata();
    assert_eq!(
        m.get("source"),
        Some("multistream_force.csv,multistream_position.csv,multistream_vib_packed.csv")
    );
    let bytes = std::fs::read(fixture("multistream_vib_packed.csv")).unwrap();
    assert_eq!(
        m.get("source_3_sha256"),
        Some(capture::sha256_hex(&bytes).as_str())
    );
    assert_eq!(m.get("source_3_map"), Some("time_s=t[ms],accel_x_mps2=acc[g]"));
    assert_eq!(m.get("source_3_rate_hz"), Some("2200"));
    assert_eq!(
        m.get("source_2_map"),
        Some("time_s=t[ms],tangential_position_m=x[mm]")
    );

    // Keeping the first of the repeated force rows instead of their mean is off by their
    // 0.05 N spread: the join did merge them.
    let dropped = dir.path().join("dropped.csv");
    success(import_multistream(
        &dropped,
        MULTISTREAM_MAP,
        &["--repeated-time", "drop"],
    ));
    let d = Capture::read_file(&dropped, CaptureKind::Rubbing).unwrap();
    let worst = d
        .time()
        .iter()
        .zip(d.column("normal_force_n").unwrap())
        .map(|(&t, &v)| (v - multistream_fz_n(t)).abs())
        .fold(0.0, f64::max);
    assert!(worst > 0.01, "{worst}");
}

#[test]
fn joining_errors_name_the_files() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("trial.csv");
    // `t` is in every input: as a position it is ambiguous.
    let map = "time_s=t[ms],normal_force_n=Fz,tangential_position_m=t[mm]";
    let o = import_multistream(&out, map, &["--repeated-time", "mean"]);
    let t = text(&o);
    assert!(!o.status.success(), "{t}");
    assert!(
        t.contains("multistream_force.csv")
            && t.contains("multistream_position.csv")
            && t.contains("multistream_vib_packed.csv")
            && t.contains("`N:t`"),
        "{t}"
    );
    // A column no input has: every input's columns are listed.
    let map = "time_s=t[ms],normal_force_n=Fz,tangential_position_m=pos[mm]";
    let o = import_multistream(&out, map, &["--repeated-time", "mean"]);
    let t = text(&o);
    assert!(!o.status.success(), "{t}");
    assert!(
        t.contains("no input has a column `pos`") && t.contains("multistream_position.csv has t, x, valid"),
        "{t}"
    );
    // Packed samples mapped without --unroll: the error says which --unroll makes the column.
    let o = import_multistream_with(&out, MULTISTREAM_MAP, &["--repeated-time", "mean"]);
    let t = text(&o);
    assert!(!o.status.success(), "{t}");
    assert!(
        t.contains("no input has a column `acc`") && t.contains("--unroll 'acc=acc_0..acc_21'"),
        "{t}"
    );
    // A clock offset that moves the position log past the others' end.
    let o = import_multistream(
        &out,
        MULTISTREAM_MAP,
        &["--repeated-time", "mean", "--clock-offset-s", "2=10"],
    );
    let t = text(&o);
    assert!(!o.status.success(), "{t}");
    assert!(
        t.contains("overlap for 0 sample(s)") && t.contains("multistream_position.csv spans 10.0417 s"),
        "{t}"
    );
    assert!(!out.exists());
    // A qualified source reads that input without looking at the others.
    let map = "time_s=t[ms],normal_force_n=Fz,tangential_position_m=2:x[mm],accel_x_mps2=3:acc[g]";
    success(import_multistream(&out, map, &["--repeated-time", "mean"]));
    let c = Capture::read_file(&out, CaptureKind::Rubbing).unwrap();
    assert_eq!(
        c.metadata().get("source_2_map"),
        Some("time_s=t[ms],tangential_position_m=2:x[mm]")
    );
}

#[test]
fn an_output_that_is_an_input_is_refused_and_the_input_kept() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("log.csv");
    let content = "t,x,Fz\n0,1,0.3\n0.001,2,0.3\n0.002,3,0.3\n";
    std::fs::write(&input, content).unwrap();
    // The same file by another path is the same file.
    let other_path = dir.path().join(".").join("log.csv");
    let o = import(
        &input,
        &other_path,
        &["--map", "time_s=t,tangential_position_m=x,normal_force_n=Fz"],
    );
    let t = text(&o);
    assert!(!o.status.success(), "{t}");
    assert!(t.contains("is this input") && t.contains("log.csv"), "{t}");
    assert_eq!(std::fs::read_to_string(&input).unwrap(), content);
}

#[test]
fn an_unknown_column_among_very_many_is_named_in_a_short_message() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("wide.csv");
    let header: Vec<String> = (0..100_000).map(|i| format!("channel_{i}")).collect();
    let row: Vec<&str> = vec!["0"; header.len()];
    std::fs::write(
        &input,
        format!("{}\n{}\n{}\n", header.join(","), row.join(","), row.join(",")),
    )
    .unwrap();
    let out = dir.path().join("out.csv");
    let o = import(
        &input,
        &out,
        &["--map", "time_s=t,tangential_position_m=x,normal_force_n=Fz"],
    );
    let t = text(&o);
    assert!(!o.status.success(), "{t}");
    assert!(t.contains("no column `t`") && t.contains("more"), "{t}");
    assert!(t.len() < 1000, "{} bytes: {}", t.len(), &t[..200]);
}

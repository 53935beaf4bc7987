//! The command line as a user meets it.

#![allow(clippy::unwrap_used)] // A failed unwrap is a failed test.

use std::path::{Path, PathBuf};

use crate::common::{json, palpus, succeeds, text};

use capture::{Capture, CaptureKind};

/// The committed Li & Bi capture set.
fn li_bi_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/captures/li_bi")
}

#[test]
fn help_explains_the_commands() {
    let o = palpus(&["--help"]);
    assert!(o.status.success());
    let t = text(&o);
    assert!(t.contains("identified dynamics") && t.contains("gen"), "{t}");
    let o = palpus(&["gen", "--help"]);
    assert!(o.status.success());
    let t = text(&o);
    for needle in [
        "--out",
        "--seed",
        "--only",
        "li_bi",
        "nakano",
        "sinapov",
        "same seed",
    ] {
        assert!(t.contains(needle), "`{needle}` missing from:\n{t}");
    }
}

#[test]
fn bad_arguments_are_clear_errors() {
    let o = palpus(&["gen", "--out", "x", "--only", "bogus"]);
    assert!(!o.status.success());
    assert!(text(&o).contains("unknown capture set `bogus`"), "{}", text(&o));
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("a_file");
    std::fs::write(&file, "not a folder").unwrap();
    let out = file.join("captures");
    let o = palpus(&["gen", "--out", out.to_str().unwrap(), "--only", "li_bi"]);
    assert!(!o.status.success());
    let t = text(&o);
    assert!(
        t.starts_with("error: generating captures into") && t.contains("a_file"),
        "{t}"
    );
}

/// `palpus gen --only li_bi` reproduces the committed capture set. Values are compared to
/// 1e-9 relative rather than as bytes, so a platform whose libm differs in the last bit still
/// passes.
#[test]
fn gen_reproduces_the_committed_li_bi_set() {
    let dir = tempfile::tempdir().unwrap();
    let t = text(&succeeds(&[
        "gen",
        "--out",
        dir.path().to_str().unwrap(),
        "--only",
        "li_bi",
        "--seed",
        "1",
    ]));
    assert!(t.contains("li_bi_needle") && t.contains("total"), "{t}");
    let committed = li_bi_dir();
    for name in [
        "hard_contact_train",
        "hard_contact_test",
        "soft_contact_train",
        "soft_contact_test",
        "needle_train",
        "needle_test",
    ] {
        let kind = if name.starts_with("needle") {
            CaptureKind::Insertion
        } else {
            CaptureKind::Rubbing
        };
        same_capture(
            &dir.path().join(format!("li_bi/{name}.csv")),
            &committed.join(format!("{name}.csv")),
            kind,
        );
    }
}

/// `fresh` holds what `kept` holds: the same columns, metadata keys and values to 1e-9.
fn same_capture(fresh: &Path, kept: &Path, kind: CaptureKind) {
    let name = kept.display();
    let fresh = Capture::read_file(fresh, kind).unwrap();
    let kept = Capture::read_file(kept, kind).unwrap();
    assert_eq!(fresh.columns(), kept.columns(), "{name}");
    assert_eq!(fresh.len(), kept.len(), "{name}");
    let keys = |c: &Capture| {
        c.metadata()
            .extra()
            .iter()
            .map(|(k, _)| k.clone())
            .collect::<Vec<_>>()
    };
    assert_eq!(keys(&fresh), keys(&kept), "{name}");
    for (a, b) in fresh.data().iter().zip(kept.data()) {
        for (x, y) in a.iter().zip(b) {
            assert!((x - y).abs() <= 1e-9 * x.abs().max(1e-3), "{name}: {x} vs {y}");
        }
    }
}

/// The epidural scene's capture is `palpus gen --needle-tissue epidural`'s, seed 1.
#[test]
fn gen_reproduces_the_committed_epidural_capture() {
    let dir = tempfile::tempdir().unwrap();
    let t = text(&succeeds(&[
        "gen",
        "--out",
        dir.path().to_str().unwrap(),
        "--needle-tissue",
        "epidural",
    ]));
    assert!(t.contains("needle_train.csv"), "{t}");
    same_capture(
        &dir.path().join("li_bi/needle_train.csv"),
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/captures/epidural/needle_train.csv"),
        CaptureKind::Insertion,
    );
}

#[test]
fn identify_prints_the_json_report_and_writes_models() {
    let dir = tempfile::tempdir().unwrap();
    let root = li_bi_dir();
    let model = dir.path().join("needle.json");
    let libsvm = dir.path().join("needle.model");
    let report = json(&[
        "identify",
        root.join("needle_train.csv").to_str().unwrap(),
        "--model",
        "needle",
        "--test",
        root.join("needle_test.csv").to_str().unwrap(),
        "--out",
        model.to_str().unwrap(),
        "--libsvm",
        libsvm.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(report["model"], "needle");
    assert_eq!(report["n_train"], 350);
    for key in ["n_sv", "dual_objective", "fit_seconds"] {
        assert!(report[key].is_number(), "{key}");
    }
    for key in ["aise", "error_bound", "rmse"] {
        assert!(report["metrics"]["svr"][key].as_f64().unwrap() > 0.0, "{key}");
    }
    assert!(report["metrics"]["rbf_network"]["aise"].is_number());
    assert!(report["metrics"]["coulomb_viscous"].is_null());
    assert!(identify::ModelFile::load(&model).is_ok());
    assert!(
        std::fs::read_to_string(&libsvm)
            .unwrap()
            .starts_with("svm_type epsilon_svr")
    );

    let hard = root.join("hard_contact_train.csv");
    let hard = hard.to_str().unwrap();
    let report = json(&["identify", hard, "--model", "hard", "--json"]);
    assert!((report["w"].as_f64().unwrap() - 0.1647).abs() < 0.005);
    assert!(report["b"].is_number() && report["metrics"]["coulomb_viscous"]["aise"].is_number());

    // A rubbing capture given as a needle one: the reader names the file and the kind.
    let o = palpus(&["identify", hard, "--model", "needle"]);
    assert!(!o.status.success());
    assert!(
        text(&o).contains("hard_contact_train.csv") && text(&o).contains("insertion"),
        "{}",
        text(&o)
    );
}

#[test]
fn identify_search_reports_the_frontier_and_fits_the_best_point() {
    let root = li_bi_dir();
    let hard = root.join("hard_contact_train.csv");
    let report = json(&[
        "identify",
        hard.to_str().unwrap(),
        "--model",
        "hard",
        "--search",
        "--json",
    ]);
    let points = report["search"].as_array().unwrap();
    assert_eq!(points.len(), 9, "3 C × 3 ε for the linear model");
    let best = points
        .iter()
        .min_by(|a, b| {
            a["cv_aise"]
                .as_f64()
                .unwrap()
                .total_cmp(&b["cv_aise"].as_f64().unwrap())
        })
        .unwrap();
    let used = &report["hyperparameters"][0];
    assert_eq!(used["c"], best["c"]);
    assert_eq!(used["epsilon"], best["epsilon"]);
    for p in points {
        assert!(p["n_sv"].as_f64().unwrap() >= 1.0 && p["fit_seconds"].as_f64().unwrap() >= 0.0);
    }
    // --search chooses the hyperparameters itself.
    let o = palpus(&["identify", "x.csv", "--model", "hard", "--search", "--c", "1"]);
    assert!(
        !o.status.success() && text(&o).contains("cannot be used with"),
        "{}",
        text(&o)
    );

    // --grid gives the grid (and implies --search): 4 log-spaced C × the one ε given.
    let report = json(&[
        "identify",
        hard.to_str().unwrap(),
        "--model",
        "hard",
        "--grid",
        "c=1e2..1e5:4,epsilon=0.03",
        "--json",
    ]);
    let points = report["search"].as_array().unwrap();
    let mut cs: Vec<f64> = points.iter().map(|p| p["c"].as_f64().unwrap()).collect();
    cs.sort_by(f64::total_cmp);
    for (c, expected) in cs.iter().zip([1e2, 1e3, 1e4, 1e5]) {
        assert!((c / expected - 1.0).abs() < 1e-12, "{cs:?}");
    }
    assert_eq!(cs.len(), 4);
    assert!(points.iter().all(|p| p["epsilon"] == 0.03));
    // A bad grid names the item and why; a γ for the linear model is refused.
    for (spec, says) in [
        ("c=1e5..1e2:4", "runs from 100000 down to 100"),
        ("gamma=1", "has no γ"),
        ("k=3", "unknown name `k`"),
    ] {
        let o = palpus(&[
            "identify",
            hard.to_str().unwrap(),
            "--model",
            "hard",
            "--grid",
            spec,
        ]);
        assert!(
            !o.status.success() && text(&o).contains(says),
            "{spec}: {}",
            text(&o)
        );
    }
}

#[test]
fn bench_trade_writes_every_point_and_the_front_nothing_beats() {
    let root = li_bi_dir();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("trade");
    let o = palpus(&[
        "bench",
        "trade",
        root.join("hard_contact_train.csv").to_str().unwrap(),
        "--model",
        "hard",
        "--test",
        root.join("hard_contact_test.csv").to_str().unwrap(),
        "--grid",
        "c=1e1..1e7:4,epsilon=0.01..0.1:3",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("12 points (0 failed)"), "{}", text(&o));
    let csv = std::fs::read_to_string(out.join("trade.csv")).unwrap();
    let mut lines = csv.lines();
    // What was measured: the model and the training capture's bytes.
    let bytes = std::fs::read(root.join("hard_contact_train.csv")).unwrap();
    assert_eq!(
        lines.next().unwrap(),
        format!(
            "# palpus-trade format=1 model=hard capture_sha256={}",
            capture::sha256_hex(&bytes)
        )
    );
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<String>> = lines.map(|l| l.split(',').map(str::to_owned).collect()).collect();
    assert_eq!(rows.len(), 12);
    let value = |r: &Vec<String>, name: &str| r[col(name)].parse::<f64>().unwrap();
    let on: Vec<&Vec<String>> = rows.iter().filter(|r| r[col("on_front")] == "true").collect();
    assert!(!on.is_empty());
    // Held out on the test capture, and no row beats a front row on both time and error.
    for f in &on {
        let (t, e) = (value(f, "test_predict_ns"), value(f, "test_aise"));
        assert!(t > 0.0 && e > 0.0 && value(f, "test_max_error") > 0.0);
        assert!(!rows.iter().any(|r| {
            let (rt, re) = (value(r, "test_predict_ns"), value(r, "test_aise"));
            rt <= t && re <= e && (rt < t || re < e)
        }));
    }
    let image = render::Image::load_png(&out.join("trade.png")).expect("a PNG");
    assert_eq!((image.width, image.height), palpus::plots::TRADE_SIZE);
    // A bad grid is refused before anything runs.
    let o = palpus(&[
        "bench",
        "trade",
        root.join("hard_contact_train.csv").to_str().unwrap(),
        "--model",
        "hard",
        "--grid",
        "c=0",
    ]);
    assert!(
        !o.status.success() && text(&o).contains("out of range"),
        "{}",
        text(&o)
    );
}

/// Output piped into a reader that has gone (`palpus gen … | head`) ends the process as it ends
/// other tools, by SIGPIPE, without a panic message; the captures it wrote are complete.
#[cfg(unix)]
#[test]
fn a_closed_output_pipe_ends_the_process_without_a_panic() {
    use std::os::unix::process::ExitStatusExt;
    use std::process::Stdio;
    let dir = tempfile::tempdir().unwrap();
    let mut child = crate::common::palpus_command()
        .args(["gen", "--out"])
        .arg(dir.path())
        .args(["--only", "nakano"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The reader goes before the summary is written.
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(out.status.signal(), Some(13), "{:?}: {stderr}", out.status);
    // Every capture was written before the summary, whole.
    let captures = std::fs::read_dir(dir.path().join("nakano")).unwrap().count();
    assert_eq!(captures, 21);
}

/// `--threads N` sets the solvers' worker threads for any command; 0 is refused.
#[test]
fn threads_sets_the_solvers_workers_and_refuses_zero() {
    let capture = li_bi_dir().join("needle_train.csv");
    let t = text(&succeeds(&[
        "--threads",
        "1",
        "bench",
        "svr-scale",
        "--capture",
        capture.to_str().unwrap(),
        "--sizes",
        "350",
    ]));
    assert!(t.starts_with("1 solver thread\n"), "{t}");
    let e = crate::common::fails(&[
        "identify",
        capture.to_str().unwrap(),
        "--model",
        "needle",
        "--threads",
        "0",
    ]);
    assert!(e.contains("--threads"), "{e}");
}

/// `bench svr-scale --data` fits a regression table; a cell that is not a number is named by
/// file, line and column.
#[test]
fn svr_scale_fits_a_table_and_names_a_bad_cell() {
    let dir = tempfile::tempdir().unwrap();
    let table = dir.path().join("table.csv");
    let mut text = String::from("x0,x1,x2,y\n");
    for i in 0..60 {
        let (a, b, c) = (
            f64::from(i) / 60.0,
            f64::from(i * 7 % 13) / 13.0,
            f64::from(i * 3 % 11) / 11.0,
        );
        text.push_str(&format!("{a},{b},{c},{}\n", (3.0 * a).sin() + b * c));
    }
    std::fs::write(&table, &text).unwrap();
    let t = text_of(&[
        "bench",
        "svr-scale",
        "--data",
        table.to_str().unwrap(),
        "--sizes",
        "40",
        "--c",
        "10",
        "--gamma",
        "1",
        "--epsilon",
        "0.05",
    ]);
    let row = t.lines().last().unwrap();
    assert!(row.trim_start().starts_with("40 "), "{t}");
    text.push_str("0.5,half,0.1,1.0\n");
    std::fs::write(&table, &text).unwrap();
    let e = crate::common::fails(&["bench", "svr-scale", "--data", table.to_str().unwrap()]);
    assert!(
        e.contains("table.csv:62: column 2: `half` is not a finite number"),
        "{e}"
    );
}

fn text_of(args: &[&str]) -> String {
    text(&succeeds(args))
}

/// A sweep's CSV becomes a PNG and a per-problem summary: the worst and median of libsvm's
/// seconds over ours, and the fit slowest against its slower neighbour; a row without our
/// seconds is refused naming its line.
#[test]
fn a_sweep_is_drawn_and_summed_up_per_problem() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("svr_scale_plot");
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("sweep.csv");
    std::fs::write(
        &csv,
        "problem,n,ours_s,libsvm_s,our_solver\n\
         \"a b\",350,0.01,0.04,interior point\n\
         \"a b\",700,0.05,0.2,low-rank\n\
         \"a b\",1400,0.06,0.6,low-rank\n\
         \"a b\",2800,0.1,0.5,low-rank\n\
         c,350,0.02,0.01,smo\n",
    )
    .unwrap();
    let png = dir.join("sweep.png");
    let _ = std::fs::remove_file(&png);
    let said = text(&succeeds(&[
        "bench",
        "svr-scale-plot",
        csv.to_str().unwrap(),
        "--out",
        png.to_str().unwrap(),
    ]));
    // Ratios 4, 4, 10, 5: worst 4, median (4 + 5) / 2 (not the upper middle, 5); 0.05 s is
    // 0.05 / 0.06 of its slower neighbour, the first 0.01 / 0.05, 0.06 s 0.06 / 0.1, the last
    // 0.1 / 0.06 = 1.67.
    let a = said.lines().find(|l| l.starts_with("a b")).expect(&said);
    assert!(
        a.contains("4.00×") && a.contains("4.50×") && a.contains("1.67× at n = 2800"),
        "{a}"
    );
    let c = said.lines().find(|l| l.starts_with("c ")).expect(&said);
    assert!(c.contains("0.50×") && c.contains('–'), "{c}");
    assert!(std::fs::metadata(&png).unwrap().len() > 1000);
    std::fs::write(&csv, "problem,n,ours_s,libsvm_s,our_solver\nx,350,,1,smo\n").unwrap();
    let err = crate::common::fails(&[
        "bench",
        "svr-scale-plot",
        csv.to_str().unwrap(),
        "--out",
        png.to_str().unwrap(),
    ]);
    assert!(err.contains("line 2"), "{err}");
}

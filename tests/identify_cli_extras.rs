//! `palpus identify`: the out-of-domain warning, `--quiet`, and the needle's physical baseline
//! in the table.

#![allow(clippy::unwrap_used)] // A failed unwrap is a failed test.

use std::path::{Path, PathBuf};
mod common;

use common::{json, succeeds};

/// A committed Li & Bi capture.
fn li_bi(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/captures/li_bi")
        .join(format!("{name}.csv"))
        .to_str()
        .unwrap()
        .to_owned()
}

/// The needle test capture played three times faster (time / 3, velocities and rate × 3):
/// the same depths and forces at speeds the training capture never reached.
fn faster_needle(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(li_bi("needle_test")).unwrap();
    let mut lines = text.lines();
    let meta = lines.next().unwrap().replace("rate_hz=100 ", "rate_hz=300 ");
    let header = lines.next().unwrap();
    let columns: Vec<&str> = header.split(',').collect();
    let mut out = format!("{meta}\n{header}\n");
    for line in lines {
        let fields: Vec<String> = line
            .split(',')
            .zip(&columns)
            .map(|(f, &c)| {
                let v: f64 = f.parse().unwrap();
                match c {
                    "time_s" => (v / 3.0).to_string(),
                    "velocity_mps" | "commanded_velocity_mps" => (v * 3.0).to_string(),
                    _ => f.to_owned(),
                }
            })
            .collect();
        out.push_str(&fields.join(","));
        out.push('\n');
    }
    let path = dir.join("needle_fast.csv");
    std::fs::write(&path, out).unwrap();
    path
}

#[test]
fn a_test_capture_outside_the_training_range_is_warned_about_and_recorded() {
    let dir = tempfile::tempdir().unwrap();
    let fast = faster_needle(dir.path());
    let (train, fast) = (li_bi("needle_train"), fast.to_str().unwrap().to_owned());
    let args = ["identify", &train, "--model", "needle", "--test", &fast];

    let o = succeeds(&args);
    let stderr = String::from_utf8_lossy(&o.stderr);
    let warnings: Vec<&str> = stderr.lines().filter(|l| l.starts_with("warning:")).collect();
    assert_eq!(warnings.len(), 1, "{stderr}");
    let w = warnings[0];
    assert!(
        w.contains("% of test samples have velocity_mps outside the training range [")
            && w.contains("to 0.0"),
        "{w}"
    );

    let report = json(&[&args[..], &["--json"]].concat());
    let found = report["test_out_of_domain"].as_array().unwrap();
    assert_eq!(found.len(), 1, "{found:?}");
    let o = &found[0];
    assert_eq!(o["input"], "velocity_mps");
    let fraction = o["fraction"].as_f64().unwrap();
    assert!(fraction > 0.1 && fraction <= 1.0, "{o}");
    let (max, hi) = (o["max"].as_f64().unwrap(), o["range"][1].as_f64().unwrap());
    assert!(max > 2.0 * hi, "{o}");
    // The printed percentage is the recorded fraction.
    assert!(
        w.starts_with(&format!("warning: {:.1} %", fraction * 100.0)),
        "{w}"
    );
}

#[test]
fn a_test_capture_inside_the_training_range_is_not_warned_about() {
    let (train, test) = (li_bi("needle_train"), li_bi("needle_test"));
    let args = ["identify", &train, "--model", "needle", "--test", &test];
    let o = succeeds(&args);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!stderr.contains("warning"), "{stderr}");
    let report = json(&[&args[..], &["--json"]].concat());
    assert_eq!(report["test_out_of_domain"], serde_json::json!([]));
}

#[test]
fn quiet_prints_nothing_on_success_but_json_keeps_the_warnings() {
    let dir = tempfile::tempdir().unwrap();
    let fast = faster_needle(dir.path());
    let (train, fast) = (li_bi("needle_train"), fast.to_str().unwrap().to_owned());
    // Without -q this run prints the table, the row budget's note and a warning.
    for quiet in ["-q", "--quiet"] {
        let o = succeeds(&["identify", &train, "--model", "needle", "--test", &fast, quiet]);
        assert!(o.stdout.is_empty(), "{}", String::from_utf8_lossy(&o.stdout));
        assert!(o.stderr.is_empty(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let o = succeeds(&[
        "identify", &train, "--model", "needle", "--test", &fast, "-q", "--json",
    ]);
    assert!(o.stderr.is_empty(), "{}", String::from_utf8_lossy(&o.stderr));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(report["test_out_of_domain"][0]["input"], "velocity_mps");
    // Errors still show, with the same exit status.
    let o = common::palpus(&[
        "identify",
        &li_bi("hard_contact_train"),
        "--model",
        "needle",
        "-q",
    ]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("hard_contact_train.csv"));
}

#[test]
fn the_needle_table_shows_its_physical_baseline_and_why_coulomb_viscous_is_absent() {
    let (train, test) = (li_bi("needle_train"), li_bi("needle_test"));
    let o = succeeds(&["identify", &train, "--model", "needle", "--test", &test]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    let row = stdout
        .lines()
        .find(|l| l.trim_start().starts_with("Fc+c·v+k·depth"));
    let numbers: Vec<f64> = row
        .unwrap_or_else(|| panic!("{stdout}"))
        .split_whitespace()
        .skip(1)
        .map(|x| x.parse().unwrap())
        .collect();
    assert_eq!(numbers.len(), 3, "{stdout}");
    assert!(
        stdout.contains("no Coulomb+viscous") && stdout.contains("does not apply to puncture force"),
        "{stdout}"
    );
    let report = json(&["identify", &train, "--model", "needle", "--test", &test, "--json"]);
    let aise = report["metrics"]["coulomb_viscous_stiffness"]["aise"]
        .as_f64()
        .unwrap();
    assert!((aise - numbers[0]).abs() <= 1e-4 * aise, "{aise} {}", numbers[0]);

    // The friction models keep Coulomb+viscous and have no needle law.
    let hard = json(&[
        "identify",
        &li_bi("hard_contact_train"),
        "--model",
        "hard",
        "--json",
    ]);
    assert!(hard["metrics"]["coulomb_viscous_stiffness"].is_null());
    assert!(hard["metrics"]["coulomb_viscous"]["aise"].is_number());
}

#[test]
fn a_support_vector_budget_keeps_the_model_within_it_and_says_what_it_cost() {
    let (train, test) = (li_bi("needle_train"), li_bi("needle_test"));
    let args = |max_sv: Option<&str>| {
        let mut a = vec![
            "identify",
            train.as_str(),
            "--model",
            "needle",
            "--test",
            test.as_str(),
            "--json",
        ];
        if let Some(k) = max_sv {
            a.extend(["--max-sv", k]);
        }
        json(&a)
    };
    let full = args(None);
    let full_sv = full["n_sv"].as_u64().unwrap();
    assert!(full_sv > 100, "{full_sv}");
    assert!(full.get("reduction").is_none(), "{full}");
    let aise = |r: &serde_json::Value| r["metrics"]["svr"]["aise"].as_f64().unwrap();
    let mut last_deviation = 0.0;
    for k in [100u64, 50, 25] {
        let r = args(Some(&k.to_string()));
        assert_eq!(r["n_sv"].as_u64(), Some(k), "{r}");
        let red = &r["reduction"];
        assert_eq!(red["from_sv"].as_u64(), Some(full_sv), "{r}");
        let (max, rms) = (
            red["max_deviation"].as_f64().unwrap(),
            red["rms_deviation"].as_f64().unwrap(),
        );
        assert!(rms > 0.0 && rms <= max && max.is_finite(), "{red}");
        // Fewer support vectors stray further from the certified model.
        assert!(max >= last_deviation, "{k}: {max} < {last_deviation}");
        last_deviation = max;
        // The certificate is the solve's, before the reduction.
        assert_eq!(r["relative_gap"], full["relative_gap"]);
        if k == 100 {
            // Half the support vectors cost the held-out AISE under 1 %.
            assert!(aise(&r) < aise(&full) * 1.01, "{} vs {}", aise(&r), aise(&full));
        }
    }
    // A budget the model already meets changes nothing.
    let same = args(Some(&full_sv.to_string()));
    assert!(same.get("reduction").is_none(), "{same}");
    assert_eq!(aise(&same), aise(&full));
    let shown = common::fails(&["identify", &train, "--model", "needle", "--max-sv", "0"]);
    assert!(shown.contains("not a support-vector count"), "{shown}");
}

//! `palpus bench svr-scale-plot`: a sweep's fit times, drawn and summed up per problem.

use std::collections::BTreeMap;
use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use serde::Deserialize;

use crate::plots::{ScalingSeries, write_scaling_plot};

/// Draw a sweep of `bench svr-scale` fits against libsvm's (the CSV of
/// scripts/svr_scale_sweep.py) as a PNG, and print per problem the sizes, the worst and median
/// speed ratio (libsvm's seconds over ours: above 1 we are faster) and the worst spike (a fit's
/// seconds over the larger of its two neighbours').
#[derive(Debug, Args)]
pub(crate) struct SvrScalePlotArgs {
    /// The sweep: a header, then one row per fit with at least the columns problem, n, ours_s,
    /// libsvm_s (empty where libsvm was not run) and our_solver.
    #[arg(value_name = "CSV")]
    csv: PathBuf,
    /// The figure to write.
    #[arg(long, value_name = "PNG")]
    out: PathBuf,
}

#[derive(Debug, Deserialize)]
struct Row {
    problem: String,
    n: f64,
    ours_s: f64,
    libsvm_s: Option<f64>,
    our_solver: String,
}

pub(crate) fn run(args: &SvrScalePlotArgs) -> anyhow::Result<()> {
    let mut reader =
        csv::Reader::from_path(&args.csv).with_context(|| format!("reading {}", args.csv.display()))?;
    let mut problems: BTreeMap<String, Vec<Row>> = BTreeMap::new();
    let mut order: Vec<String> = Vec::new();
    for (i, row) in reader.deserialize::<Row>().enumerate() {
        // Line 1 is the header.
        let row = row.with_context(|| format!("{}: line {}", args.csv.display(), i + 2))?;
        if !(row.n > 0.0 && row.ours_s.is_finite() && row.ours_s > 0.0) {
            anyhow::bail!(
                "{}: line {}: n {} and ours_s {} must be positive",
                args.csv.display(),
                i + 2,
                row.n,
                row.ours_s
            );
        }
        if !problems.contains_key(&row.problem) {
            order.push(row.problem.clone());
        }
        problems.entry(row.problem.clone()).or_default().push(row);
    }
    if order.is_empty() {
        anyhow::bail!("{}: no fits", args.csv.display());
    }
    println!(
        "{:<28} {:>5} {:>14} {:>12} {:>12} {:>22}",
        "problem", "sizes", "n", "worst ratio", "median ratio", "worst spike"
    );
    let mut series = Vec::new();
    for name in &order {
        let mut rows = problems.remove(name).unwrap_or_default();
        rows.sort_by(|a, b| a.n.total_cmp(&b.n));
        let mut ratios: Vec<f64> = rows
            .iter()
            .filter_map(|r| r.libsvm_s.map(|l| l / r.ours_s))
            .collect();
        ratios.sort_by(f64::total_cmp);
        let spike = worst_spike(&rows);
        let ratio = |r: Option<&f64>| r.map_or("–".to_owned(), |r| format!("{r:.2}×"));
        println!(
            "{name:<28} {:>5} {:>14} {:>12} {:>12} {:>22}",
            rows.len(),
            format!("{:.0}–{:.0}", rows[0].n, rows[rows.len() - 1].n),
            ratio(ratios.first()),
            ratio(median(&ratios).as_ref()),
            spike.map_or("–".to_owned(), |(n, s)| format!("{s:.2}× at n = {n:.0}")),
        );
        series.push(ScalingSeries {
            name: name.clone(),
            ours: rows
                .iter()
                .map(|r| (r.n, r.ours_s, r.our_solver.clone()))
                .collect(),
            libsvm: rows.iter().filter_map(|r| r.libsvm_s.map(|l| (r.n, l))).collect(),
        });
    }
    write_scaling_plot(&args.out, &series)?;
    println!("wrote {}", args.out.display());
    Ok(())
}

/// The median of values sorted ascending: the mean of the middle two where their count is even.
fn median(sorted: &[f64]) -> Option<f64> {
    let middle = sorted.len() / 2;
    match sorted.len() {
        0 => None,
        n if n % 2 == 1 => Some(sorted[middle]),
        _ => Some(0.5 * (sorted[middle - 1] + sorted[middle])),
    }
}

/// The fit slowest against the larger of its neighbours' times (one neighbour at the ends):
/// (n, that ratio).
fn worst_spike(rows: &[Row]) -> Option<(f64, f64)> {
    (0..rows.len())
        .filter_map(|i| {
            let before = i.checked_sub(1).map(|j| rows[j].ours_s);
            let after = rows.get(i + 1).map(|r| r.ours_s);
            let neighbour = before.into_iter().chain(after).fold(f64::NAN, f64::max);
            neighbour
                .is_finite()
                .then(|| (rows[i].n, rows[i].ours_s / neighbour))
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))
}

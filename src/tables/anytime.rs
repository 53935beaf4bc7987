//! What `palpus recognize eval --sequential` prints: anytime decisions at each threshold, the
//! strokes that change surface part-way, and the windows that counted for little.

use std::path::PathBuf;

use recognize::RecognizerFile;
use recognize::SequentialEvaluation;

use super::recognition::percent;
use crate::session::report::{decided_after, memory_in_words, windows_in_words};

/// The anytime table of `e`, made by `model` with `others` fused into it (`paths`: the
/// recognizer's file, then theirs); `weight_given`: whether --window-weight set each window's
/// weight.
pub(crate) fn print_sequential(
    e: &SequentialEvaluation,
    model: &RecognizerFile,
    others: &[&RecognizerFile],
    weight_given: bool,
    memory_s: f64,
    paths: &[&PathBuf],
) {
    // Over travel a window's weight is scaled by the share of its samples that are new.
    let scaled = if e.window_m.is_some() {
        ", scaled by the share of its samples that are new"
    } else {
        ""
    };
    let weighed = match (weight_given, &model.posterior_weight) {
        (true, _) => " as given",
        (false, Some(_)) if others.is_empty() => ", fitted on held-out recordings",
        (false, None) if others.is_empty() => ", hop / window",
        _ => "",
    };
    println!(
        "{} on {} captures, anytime decisions over {} {} every {:.2} s from contact, \
         {} (each weighing {:.3}{weighed}{scaled}; evidence of the last {}):",
        model.method(),
        e.captures,
        e.steps,
        windows_in_words(e.window_s, e.window_m, e.friction_cutoff_m),
        e.hop_s,
        decided_after(e.decided_after_s),
        e.params.weight(),
        memory_in_words(memory_s, e.window_s, e.window_m)
    );
    if !e.fused.is_empty() {
        println!(
            "fused with the evidence of (each window's weight: {}):",
            if e.fused.iter().all(|m| m.fitted) {
                "its own, fitted on held-out recordings"
            } else {
                "its weight alone × reliability over the most reliable's"
            }
        );
        for (path, m) in paths.iter().zip(&e.fused) {
            println!(
                "  {}: {} over {} windows of {} s every {:.2} s, cross-validated accuracy {:.1} %, \
                 reliability {:.3}, weight {:.3}",
                path.display(),
                m.method,
                m.features,
                m.window_s,
                m.hop_s,
                100.0 * m.accuracy,
                m.reliability,
                m.weight
            );
        }
    }
    println!(
        "{:>9} {:>8} {:>10} {:>12} {:>14} {:>12} {:>26} {:>27} {:>10} {:>8} {:>7} {:>7}",
        "threshold",
        "named",
        "accuracy",
        "first named",
        "stable right",
        "(travel)",
        "slowest surface",
        "most travel",
        "not right",
        "flips/s",
        "Brier",
        "ECE"
    );
    let secs = |v: Option<f64>| v.map_or_else(|| "-".to_owned(), |s| format!("{s:.2} s"));
    let mm = |v: Option<f64>| v.map_or_else(|| "-".to_owned(), |m| format!("{:.1} mm", 1e3 * m));
    for r in &e.rows {
        let slowest = r
            .worst_surface
            .as_ref()
            .map_or_else(|| "-".to_owned(), |(name, s)| format!("{name} {s:.2} s"));
        let farthest = r
            .worst_surface_travel
            .as_ref()
            .map_or_else(|| "-".to_owned(), |(name, m)| format!("{name} {:.1} mm", 1e3 * m));
        println!(
            "{:>9} {:>7.1}% {:>10} {:>12} {:>14} {:>12} {:>26} {:>27} {:>10} {:>8.3} {:>7.4} {:>6.2}%",
            r.threshold,
            100.0 * r.decided as f64 / e.steps as f64,
            percent(r.accuracy()),
            secs(r.time_to_first_decision_s),
            secs(r.time_to_stable_correct_s),
            mm(r.travel_to_stable_correct_m),
            slowest,
            farthest,
            r.not_stable,
            r.flips_per_s,
            r.calibration.brier,
            100.0 * r.calibration.ece
        );
    }
    if e.rows.iter().any(|r| r.changes > 0) {
        println!(
            "strokes that slide onto another surface part-way (above: the other strokes' times; \
             named right = right for the surface under the tool):"
        );
        println!(
            "{:>9} {:>8} {:>16} {:>12} {:>16} {:>12} {:>14}",
            "threshold",
            "strokes",
            "change followed",
            "(travel)",
            "slowest change",
            "(travel)",
            "not followed"
        );
        for r in &e.rows {
            println!(
                "{:>9} {:>8} {:>16} {:>12} {:>16} {:>12} {:>14}",
                r.threshold,
                r.changes,
                secs(r.change_followed_s),
                mm(r.change_followed_m),
                secs(r.slowest_change_s),
                mm(r.slowest_change_m),
                r.changes_not_followed
            );
        }
    }
    if e.short_of_travel > 0 {
        match model.sequential_windowing().and_then(|w| w.slowest_speed_mps()) {
            Some(v) => println!(
                "{} of {} windows were rubbed slower than the slowest speed the windows read ({:.1} mm/s): \
                 each counted for the share of its travel it covered, a tool at rest for nothing",
                e.short_of_travel,
                e.steps,
                v * 1e3
            ),
            None => println!(
                "{} of {} windows held the tool at rest (it never left the {:.1} mm play): they counted for \
                 nothing",
                e.short_of_travel,
                e.steps,
                recognize::TRAVEL_PLAY_M * 1e3
            ),
        }
    }
}

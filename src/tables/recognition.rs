//! What `palpus recognize` prints of a recognizer and its evaluations: the training summary,
//! the tables of an evaluation, and their JSON objects.

use recognize::{
    CLEAR_MARGIN_Z, CV_FOLDS, ConfusionMatrix, DefaultChoice, Evaluation, FusedEvaluation, Outcome,
    RecognizerBody, RecognizerFile, WINDOW_SVM_FALLBACK_C,
};

/// Warns on stderr about each SOM whose nodes leave classes unnamed, naming them.
pub(crate) fn warn_unmapped(model: &RecognizerFile) {
    for m in model.classes_without_nodes() {
        let map = m
            .behaviour
            .map_or_else(|| "the map".to_owned(), |b| format!("the map of behaviour {b}"));
        eprintln!(
            "warning: {} of {} classes own no node of {map} ({} nodes) and can never be recognized: {}; more nodes (--nodes) may help",
            m.classes.len(),
            model.classes.len(),
            m.nodes,
            m.classes.join(", ")
        );
    }
}

/// The table the defaults were chosen from, one candidate a line, the chosen one marked.
pub(crate) fn print_default_choice(choice: &DefaultChoice) {
    let spent_s: f64 = choice
        .rows
        .iter()
        .map(|r| match r.outcome {
            Outcome::Scored { seconds, .. } | Outcome::Stopped { seconds } => seconds,
            _ => 0.0,
        })
        .sum();
    println!(
        "chosen by {}-fold cross-validation by recording on the training captures (windows every {} s; {spent_s:.1} s, \
         budget {} s; a later candidate must be more accurate by {CLEAR_MARGIN_Z} standard errors):",
        choice.folds, choice.hop_s, choice.budget_s
    );
    println!(
        "  {:>8} {:>9} {:>7}  candidate",
        "accuracy", "decisions", "seconds"
    );
    for (i, row) in choice.rows.iter().enumerate() {
        let mark = if i == choice.chosen { "  <- chosen" } else { "" };
        let what = row.candidate.describe();
        match &row.outcome {
            Outcome::Scored {
                accuracy,
                decisions,
                seconds,
            } => println!(
                "  {:>7.1}% {decisions:>9} {seconds:>7.1}  {what}{mark}",
                100.0 * accuracy
            ),
            Outcome::Failed { reason } => {
                println!("  {:>8} {:>9} {:>7}  {what}{mark}: {reason}", "failed", "", "")
            }
            Outcome::NotTried => println!(
                "  {:>8} {:>9} {:>7}  {what}{mark} (the budget was spent)",
                "not tried", "", ""
            ),
            Outcome::Stopped { seconds } => println!(
                "  {:>8} {:>9} {seconds:>7.1}  {what}{mark} (stopped when the budget ran out)",
                "stopped", ""
            ),
        }
    }
}

/// The C of an SVM over windows, and how it was chosen.
pub(crate) fn print_window_c(model: &RecognizerFile) {
    if let RecognizerBody::SvmWindows { svc, c_search, .. } = &model.body {
        let c = svc.params().c;
        match c_search {
            Some(search) if search.grid.len() > 1 => {
                let grid: Vec<String> = search
                    .grid
                    .iter()
                    .map(|p| format!("{:e}: {:.3}", p.c, p.accuracy))
                    .collect();
                let over = match search.vector_weight {
                    Some(w) => format!(" (on 1 window in {w:.1}, each at C × {w:.1})"),
                    None => String::new(),
                };
                println!(
                    "C = {c:e} chosen by {}-fold cross-validation by run{over} from {}",
                    search.folds,
                    grid.join(", ")
                );
                if let Some(from) = search.separable_from
                    && search.grid.last().is_some_and(|p| p.c > from)
                {
                    println!(
                        "  from C = {from:e} on no multiplier reached C in any fold: the classes were \
                         separated, and each larger C has the same machines (not refitted)"
                    );
                }
            }
            Some(_) => println!("C = {c:e} (given)"),
            None if c == WINDOW_SVM_FALLBACK_C => {
                println!("C = {c:e} (not cross-validated: a surface has captures of a single run or trial)")
            }
            None => println!("C = {c:e} (given; not cross-validated)"),
        }
    }
}

/// How a k-NN over windows' votes became probabilities.
pub(crate) fn print_vote_calibration(model: &RecognizerFile) {
    if let RecognizerBody::KnnWindows { calibration, .. } = &model.body {
        match calibration {
            Some(c) => println!(
                "window probabilities: {:.3} × the vote fractions + {:.3} spread over the surfaces, fitted on {} windows \
                 held out in {}-fold cross-validation by run (accuracy {:.1} %, log-loss {:.3} nats; {:.1} % of them \
                 got no vote for their surface)",
                c.votes_weight,
                1.0 - c.votes_weight,
                c.windows,
                c.folds,
                100.0 * c.accuracy,
                c.log_loss,
                100.0 * c.unvoted
            ),
            None => println!(
                "window probabilities: the raw vote fractions (not calibrated: a surface has captures of a single \
                 run or trial, or holding one out leaves fewer windows than k), so this k-NN cannot be fused"
            ),
        }
    }
}

/// The weight of a window in anytime decisions, and how it was set.
pub(crate) fn print_posterior_weight(model: &RecognizerFile) {
    let Some(hop) = model.hop_weight() else {
        return;
    };
    match &model.posterior_weight {
        Some(p) => {
            println!(
                "posterior weight {:.3} a window (hop / window {hop:.3}), fitted on {} windows held out in {}-fold \
                 cross-validation by run, over a memory of {} s: Brier score {:.3} against {:.3}",
                p.weight, p.windows, p.folds, p.memory_s, p.brier, p.hop_brier
            );
            if let Some(h) = &p.held_out {
                println!("  anytime decisions at that weight, {h}");
            }
        }
        None => println!(
            "posterior weight hop / window, {hop:.3} a window (not fitted: a surface has captures of a single run \
             or trial, --no-weight-fit was given, or a fold's refit could not stand for this recognizer)"
        ),
    }
}

/// Each behaviour's cross-validated accuracy (its fusion weight) and, for an SVM, its C.
pub(crate) fn print_reliabilities(model: &RecognizerFile, trained_s: f64) {
    let reliabilities = model.reliabilities();
    if reliabilities.is_empty() {
        return;
    }
    println!(
        "trained in {trained_s:.2} s; reliability weights (accuracy under cross-validation by trial, at most {CV_FOLDS} folds):"
    );
    for r in &reliabilities {
        let name = r.behaviour.unwrap_or("(no behaviour)");
        let weight = match (r.reliability, r.folds) {
            (Some(a), Some(folds)) => format!("{a:.3} ({folds} folds)"),
            (Some(a), None) => format!("{a:.3}"),
            _ => "none (too few trials to cross-validate): fused with the mean of the others' weights, or all equal"
                .to_owned(),
        };
        let c = match (r.c, r.c_search) {
            (Some(c), Some(search)) if search.grid.len() > 1 => {
                let grid: Vec<String> = search
                    .grid
                    .iter()
                    .map(|p| format!("{:e}: {:.3}", p.c, p.accuracy))
                    .collect();
                format!("; C = {c:e} chosen from {}", grid.join(", "))
            }
            (Some(c), Some(_)) => format!("; C = {c:e} (given)"),
            (Some(c), None) => format!("; C = {c:e} (not cross-validated)"),
            (None, _) => String::new(),
        };
        println!("  {name:<16} {weight}{c}");
    }
}

/// Warns on stderr about each capture that gave no decision window (once per capture, however
/// many rounds held it out): the evaluation scores it as never correct rather than failing, so
/// that the other captures are still scored; with no decision at all, evaluating is an error.
pub(crate) fn warn_windowless(e: &Evaluation) {
    let mut seen = std::collections::BTreeSet::new();
    for w in e.windowless.iter().filter(|w| seen.insert(&w.path)) {
        eprintln!(
            "warning: {w}; it gives no decision at a {:.3} s window and counts as never correct",
            e.window_s
        );
    }
}

/// An evaluation's summary line, confusion matrix and timing.
pub(crate) fn print_evaluation(e: &Evaluation, what: &str) {
    println!(
        "{what}, {} decisions; window {:.3} s, decision latency {:.3} s",
        e.confusion.total(),
        e.window_s,
        e.decision_latency_s
    );
    print!("{}", e.confusion.to_text());
    let secs = |v: Option<f64>| v.map_or_else(|| "-".to_owned(), |s| format!("{s:.3} s"));
    println!(
        "time to first correct {} ({} captures never correct), to stable {} ({} not stable at the end), {:.3} flips/s",
        secs(e.time_to_first_correct_s),
        e.never_correct,
        secs(e.time_to_stable_s),
        e.not_stable,
        e.flips_per_s
    );
}

pub(crate) fn percent(a: Option<f64>) -> String {
    a.map_or_else(|| "-".to_owned(), |a| format!("{:.1} %", 100.0 * a))
}

pub(crate) fn print_fused(f: &FusedEvaluation) {
    println!("each behaviour alone:");
    for b in &f.per_behaviour {
        println!(
            "  {:<16} {:>7} of {} scratches (fusion weight {:.3})",
            b.behaviour.as_deref().unwrap_or("(no behaviour)"),
            percent(b.confusion.accuracy()),
            b.confusion.total(),
            b.weight
        );
    }
    println!(
        "fused over behaviours: {} trials (surface, trial), {} of more than one scratch",
        f.groups, f.multi_scratch_groups
    );
    print!("{}", f.confusion.to_text());
    println!(
        "fused {} vs best single behaviour {}",
        percent(f.confusion.accuracy()),
        percent(f.best_single_accuracy())
    );
}

pub(crate) fn per_class_json(c: &ConfusionMatrix<String>) -> serde_json::Value {
    c.classes()
        .iter()
        .zip(c.per_class_rates())
        .map(|(c, r)| (c.clone(), r.into()))
        .collect::<serde_json::Map<String, serde_json::Value>>()
        .into()
}

pub(crate) fn fused_json(f: &FusedEvaluation) -> serde_json::Value {
    let per_behaviour: serde_json::Map<String, serde_json::Value> = f
        .per_behaviour
        .iter()
        .map(|b| {
            (
                b.behaviour.clone().unwrap_or_default(),
                serde_json::json!({
                    "accuracy": b.confusion.accuracy(),
                    "scratches": b.confusion.total(),
                    "weight": b.weight,
                    "per_class": per_class_json(&b.confusion),
                }),
            )
        })
        .collect();
    serde_json::json!({
        "accuracy": f.confusion.accuracy(),
        "per_class": per_class_json(&f.confusion),
        "classes": f.confusion.classes(),
        "confusion": f.confusion.counts(),
        "groups": f.groups,
        "multi_scratch_groups": f.multi_scratch_groups,
        "best_single_accuracy": f.best_single_accuracy(),
        "per_behaviour": per_behaviour,
    })
}

pub(crate) fn to_json(e: &Evaluation) -> serde_json::Value {
    let per_class: serde_json::Map<String, serde_json::Value> = e
        .confusion
        .classes()
        .iter()
        .zip(e.confusion.per_class_rates())
        .map(|(c, r)| (c.clone(), r.into()))
        .collect();
    serde_json::json!({
        "method": e.method,
        "accuracy": e.confusion.accuracy(),
        "per_class": per_class,
        "classes": e.confusion.classes(),
        "confusion": e.confusion.counts(),
        "window_s": e.window_s,
        "decision_latency_s": e.decision_latency_s,
        "time_to_first_correct_s": e.time_to_first_correct_s,
        "time_to_stable_s": e.time_to_stable_s,
        "flips_per_s": e.flips_per_s,
        "captures": e.captures,
        "never_correct": e.never_correct,
        "not_stable": e.not_stable,
    })
}

/// Accuracy against decision window, one row per evaluation.
pub(crate) fn print_windows(method: &str, captures: usize, evaluations: &[Evaluation]) {
    println!(
        "{} on {} captures, accuracy against decision window:",
        method, captures
    );
    println!(
        "{:>9} {:>9} {:>10} {:>9} {:>14} {:>14} {:>8} {:>9}",
        "window", "latency", "accuracy", "worst", "first correct", "stable", "flips/s", "decisions"
    );
    let secs = |v: Option<f64>| v.map_or_else(|| "-".to_owned(), |s| format!("{s:.2} s"));
    for e in evaluations {
        let worst = e
            .confusion
            .per_class_rates()
            .into_iter()
            .flatten()
            .reduce(f64::min);
        println!(
            "{:>7.2} s {:>7.2} s {:>10} {:>9} {:>14} {:>14} {:>8.2} {:>9}",
            e.window_s,
            e.decision_latency_s,
            percent(e.confusion.accuracy()),
            percent(worst),
            secs(e.time_to_first_correct_s),
            secs(e.time_to_stable_s),
            e.flips_per_s,
            e.confusion.total()
        );
    }
}

//! What `palpus recognize cv` prints: the pooled evaluation, each behaviour alone, and the
//! behaviours fused by how many, as tables or as one JSON object.

use recognize::TrainSettings;
use recognize::protocol::{ProtocolResult, Split};

use super::recognition::{per_class_json, percent, print_evaluation, to_json};

/// The JSON object of a cross-validation.
pub(crate) fn cv_json(
    result: &ProtocolResult,
    settings: &TrainSettings,
    split: Split,
    fold: Option<usize>,
) -> serde_json::Value {
    let e = &result.evaluation;
    let by_count = result.fused_by_count();
    let mut json = to_json(e);
    if let Some(object) = json.as_object_mut() {
        object.insert("features".to_owned(), settings.features.name().into());
        object.insert("split".to_owned(), split.name().into());
        object.insert("folds".to_owned(), split.folds().into());
        object.insert("fold".to_owned(), fold.into());
        object.insert("seeds".to_owned(), result.seeds.into());
        object.insert("rounds".to_owned(), result.rounds.into());
        let per_behaviour: serde_json::Map<String, serde_json::Value> = result
            .per_behaviour
            .iter()
            .map(|(b, m)| {
                (
                    b.clone().unwrap_or_default(),
                    serde_json::json!({
                        "accuracy": m.accuracy(),
                        "scratches": m.total(),
                        "per_class": per_class_json(m),
                    }),
                )
            })
            .collect();
        object.insert("per_behaviour".to_owned(), per_behaviour.into());
        let counts: Vec<serde_json::Value> = by_count
            .iter()
            .map(|c| {
                serde_json::json!({
                    "behaviours": c.behaviours,
                    "combinations": c.combinations,
                    "mean_accuracy": c.mean_accuracy,
                    "min_accuracy": c.min_accuracy,
                    "max_accuracy": c.max_accuracy,
                })
            })
            .collect();
        object.insert("fused_by_count".to_owned(), counts.into());
        let combinations: Vec<serde_json::Value> = result
            .combinations
            .iter()
            .map(|c| {
                serde_json::json!({
                    "behaviours": c.behaviours,
                    "accuracy": c.confusion.accuracy(),
                    "trials": c.confusion.total(),
                })
            })
            .collect();
        object.insert("combinations".to_owned(), combinations.into());
        if let Some(all) = result.fused_all() {
            object.insert(
                "fused".to_owned(),
                serde_json::json!({
                    "accuracy": all.confusion.accuracy(),
                    "per_class": per_class_json(&all.confusion),
                    "confusion": all.confusion.counts(),
                    "trials": all.confusion.total(),
                    "best_single_accuracy": result.best_single_accuracy(),
                }),
            );
        }
    }
    json
}

/// The tables of a cross-validation that took `elapsed_s`.
pub(crate) fn print_cv(
    result: &ProtocolResult,
    settings: &TrainSettings,
    split: Split,
    fold: Option<usize>,
    elapsed_s: f64,
) {
    let e = &result.evaluation;
    let by_count = result.fused_by_count();
    print_evaluation(
        e,
        &format!(
            "{} over {} features, {} split, {} x {} seed(s) = {} recognizers in {elapsed_s:.1} s; pooled over {} evaluations of held-out captures",
            e.method,
            settings.features,
            split.name(),
            fold.map_or_else(
                || format!("{} folds", split.folds()),
                |f| format!("fold {f} of {}", split.folds())
            ),
            result.seeds,
            result.rounds,
            e.captures
        ),
    );
    if result.per_behaviour.is_empty() {
        return;
    }
    println!("each behaviour alone:");
    for (b, m) in &result.per_behaviour {
        println!(
            "  {:<16} {:>7} of {} scratches",
            b.as_deref().unwrap_or("(no behaviour)"),
            percent(m.accuracy()),
            m.total()
        );
    }
    println!("behaviours fused, by how many (mean, worst and best of every combination):");
    for c in &by_count {
        println!(
            "  {} ({:>2} combinations): {:>7}  [{} – {}]",
            c.behaviours,
            c.combinations,
            percent(Some(c.mean_accuracy)),
            percent(Some(c.min_accuracy)),
            percent(Some(c.max_accuracy))
        );
    }
    if let Some(all) = result.fused_all() {
        println!(
            "all {} fused, {} trials:",
            all.behaviours.len(),
            all.confusion.total()
        );
        print!("{}", all.confusion.to_text());
        println!(
            "fused {} vs best single behaviour {}",
            percent(all.confusion.accuracy()),
            percent(result.best_single_accuracy())
        );
    }
}

//! The session report: a folder with the summary (text and JSON), force plots (PNG, drawn by
//! [`crate::plots::session`]), a rendered frame (or why none could be made) and the
//! recognized-surface timeline.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use recognize::PosteriorWeight;
use serde::Serialize;

use super::analysis::SegmentSummary;
use crate::models::{BudgetChoice, Origin, ResolvedModel};

/// Why a report could not be written.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// A file could not be written.
    #[error("writing {}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
}

/// One recognized-surface decision.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Recognition {
    /// The object being rubbed.
    pub object: String,
    /// The surface it really is.
    pub truth: String,
    /// Loop time of the decision within the segment, s.
    pub time_s: f64,
    /// The surface named; `None` while the recognizer is undecided (its posterior below the
    /// threshold).
    pub label: Option<String>,
    /// The most probable surface, named or not.
    pub best: String,
    /// Confidence 0–1 of `best` (a k-NN's or SVM's posterior, a SOM's margin).
    pub confidence: f64,
}

/// How soon one surface segment's surface was named.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SurfaceTiming {
    /// The object being rubbed.
    pub object: String,
    /// The surface it really is.
    pub truth: String,
    /// Loop time of the stroke's first tick, s.
    pub stroke_s: f64,
    /// How soon it was named, from the stroke's start; travel is the tool's path read through
    /// the play ([`recognize::PlayedPath`]).
    #[serde(flatten)]
    pub timing: recognize::DecisionTiming,
}

/// A model as the report lists it.
#[derive(Debug, Clone, Serialize)]
pub struct ModelLine {
    /// The scene's name for it.
    pub name: String,
    /// Its role.
    pub role: String,
    /// `file`, `cache` or `identified`.
    pub origin: String,
    /// The file it came from or was cached to.
    pub path: PathBuf,
    /// Fitting time when identified now, s.
    pub fit_s: Option<f64>,
    /// Support vectors.
    pub training_samples: usize,
    /// The point a scene's budget picked from a measured trade.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub budget: Option<BudgetChoice>,
}

impl ModelLine {
    /// From a resolved model.
    pub fn new(m: &ResolvedModel) -> Self {
        let (origin, path, fit_s) = match &m.origin {
            Origin::File(p) => ("file", p.clone(), None),
            Origin::Cached(p) => ("cache", p.clone(), None),
            Origin::Identified { cached, seconds } => ("identified", cached.clone(), Some(*seconds)),
        };
        Self {
            name: m.name.clone(),
            role: m.role.to_string(),
            origin: origin.into(),
            path,
            fit_s,
            training_samples: m.model.n_train,
            budget: m.budget.clone(),
        }
    }
}

/// A scene's surface recognizer, as the report names it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RecognizerLine {
    /// `som`, `knn` or `svm`.
    pub method: String,
    /// The features it decides on.
    pub features: String,
    /// Its decision window and hop, s.
    pub window_s: f64,
    pub hop_s: f64,
    /// For windows over travel, the travel a window spans, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub window_m: Option<f64>,
    /// For friction filtered over travel, the filter's cut-off wavelength, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub friction_cutoff_m: Option<f64>,
    /// How long after its last sample a window is decided, s (the filters' lookahead, or 0
    /// with a mirrored end).
    pub decided_after_s: f64,
    /// Posterior at which a k-NN or SVM names a surface (a SOM names one every window).
    pub threshold: Option<f64>,
    /// Span of windows whose evidence counts, s.
    pub memory_s: Option<f64>,
    /// Likelihood ratio at which the change test drops the evidence before a change; `None`
    /// without one.
    pub change_odds: Option<f64>,
    /// The exponent a window of whole evidence is raised to in the posterior (the recognizer's
    /// weight fitted on held-out recordings, else hop / window).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub window_weight: Option<f64>,
    /// Where that weight came from.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub window_weight_from: Option<WindowWeightFrom>,
}

/// Where a window's weight in the posterior came from, so that a report read later says whether
/// the confidence it shows was calibrated on recordings the recognizer never saw.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "snake_case", tag = "from")]
pub enum WindowWeightFrom {
    /// Fitted on recordings held out of training: the file's fit, with `hop / window` and the
    /// memory it was fitted over.
    HeldOut(PosteriorWeight),
    /// `hop / window`, every sample counted once: the file carries no fit (written before fits
    /// were made, trained on a single recording, or with `--no-weight-fit`).
    HopWindow,
}

impl WindowWeightFrom {
    /// Where the weight of `model`'s windows comes from; `None` for a recognizer without window
    /// probabilities (a SOM).
    pub fn of(model: &recognize::RecognizerFile) -> Option<Self> {
        model.hop_weight()?;
        Some(
            model
                .posterior_weight
                .clone()
                .map_or(Self::HopWindow, Self::HeldOut),
        )
    }

    /// The words after the weight in the report of a posterior keeping `memory_s`.
    fn words(&self, memory_s: f64) -> String {
        match self {
            Self::HeldOut(fit) => {
                let elsewhere = if fit.fitted_at_memory(memory_s) {
                    String::new()
                } else {
                    format!(" over a memory of {} s, not this one,", fit.memory_s)
                };
                format!(
                    " as fitted on held-out recordings{elsewhere} rather than hop / window's {:.3}",
                    fit.hop_weight
                )
            }
            Self::HopWindow => " (hop / window)".to_owned(),
        }
    }
}

/// The whole report (`report.json`).
#[derive(Debug, Clone, Serialize)]
pub struct SessionReport {
    /// The scene's name.
    pub scene: String,
    /// The scene file.
    pub scene_file: PathBuf,
    /// The device.
    pub device: String,
    /// Models used.
    pub models: Vec<ModelLine>,
    /// Per segment.
    pub segments: Vec<SegmentSummary>,
    /// The surface recognizer and the settings it decided with.
    pub recognizer: Option<RecognizerLine>,
    /// Recognized-surface decisions, undecided ones included.
    pub recognition: Vec<Recognition>,
    /// Fraction of the decisions that named a surface that named the right one.
    pub recognition_accuracy: Option<f64>,
    /// Per surface segment, how soon its surface was named.
    pub recognition_timing: Vec<SurfaceTiming>,
    /// Samples whose window the recognizer could not read
    /// ([`haptics::flag::RECOGNIZER_WINDOW_UNREAD`]: slid faster than its spectra's
    /// bands reach); each added no evidence.
    pub recognition_unread_windows: usize,
    /// The rendered frame, or why there is none.
    pub frame: Result<PathBuf, String>,
    /// Captures recorded.
    pub recorded: Vec<(PathBuf, u64)>,
    /// The last attempt scored against the scene's goal, when it states one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub score: Option<super::score::Score>,
    /// Every attempt (each stroke into the tissue and out), in order; a headless session makes
    /// one.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub attempts: Vec<super::score::Score>,
    /// Wall-clock time from start to report, s.
    pub wall_s: f64,
}

impl SessionReport {
    /// The summary printed to the terminal and written to `summary.txt`.
    pub fn to_text(&self) -> String {
        let mut t = String::new();
        let _ = writeln!(
            t,
            "scene {} ({}) on {}",
            self.scene,
            self.scene_file.display(),
            self.device
        );
        for m in &self.models {
            let how = match m.fit_s {
                Some(s) => format!("identified in {s:.2} s, cached at {}", m.path.display()),
                None => format!("{} {}", m.origin, m.path.display()),
            };
            let _ = writeln!(
                t,
                "  model {} ({}): {} training samples, {how}",
                m.name, m.role, m.training_samples
            );
            if let Some(b) = &m.budget {
                let _ = writeln!(t, "    chosen {b}");
            }
        }
        for s in &self.segments {
            let _ = writeln!(
                t,
                "  {} [{}]: {:.2} s, {} ticks, mean rate {:.2} Hz ({:+.3} %), period error p99 {:.0} µs, {} ticks > 2 ms late, {} slots skipped, {} stalls (longest {:.1} ms)",
                s.object,
                s.kind,
                s.duration_s,
                s.ticks,
                s.mean_rate_hz,
                100.0 * (s.mean_rate_hz - s.nominal_rate_hz) / s.nominal_rate_hz.max(1e-9),
                s.period_error_p99_us,
                s.late_over_2ms,
                s.missed_slots,
                s.stalls,
                s.longest_stall_ms
            );
            let _ = writeln!(
                t,
                "    force sent ≤ {:.2} N (limit {:.0} N), {} non-finite, {} safety events, {} model clamps; ended: {}",
                s.max_command_n,
                s.device_limit_n,
                s.non_finite_commands,
                s.safety_events,
                s.model_clamps,
                s.outcome
            );
            if let Some(w) = &s.device_watchdog {
                let _ = writeln!(t, "    {w}");
            }
            for o in &s.out_of_domain {
                let _ = writeln!(
                    t,
                    "    outside the model's trained domain: {} ticks while {} at {:.1}–{:.1} mm, {:.1}–{:.1} mm/s (rendered at the nearest trained input)",
                    o.ticks,
                    o.state.replace('_', " "),
                    o.depth_m[0] * 1e3,
                    o.depth_m[1] * 1e3,
                    o.velocity_mps[0] * 1e3,
                    o.velocity_mps[1] * 1e3
                );
            }
            // A model of no simulated tissue is compared with none.
            let tissue = s.truth_tissue.as_deref().unwrap_or_default();
            for (i, p) in s.punctures.iter().enumerate() {
                let truth = p
                    .truth_depth_m
                    .map_or("-".to_owned(), |d| format!("{:.1} mm", d * 1e3));
                let truth_peak = p.truth_peak_force_n.map_or("-".to_owned(), |f| {
                    format!("{f:.2} N, {:+.0} %", 100.0 * (p.peak_force_n - f) / f)
                });
                let compared = if s.truth_tissue.is_some() {
                    (
                        format!(" (simulated {tissue} at {:.1} mm/s: {truth})", p.speed_mps * 1e3),
                        format!(" (simulated {tissue}: {truth_peak})"),
                    )
                } else {
                    (format!(" at {:.1} mm/s", p.speed_mps * 1e3), String::new())
                };
                let _ = writeln!(
                    t,
                    "    puncture {} at {:.2} s: depth {:.1} mm{}, peak {:.2} N{}",
                    i + 1,
                    p.time_s,
                    p.depth_m * 1e3,
                    compared.0,
                    p.peak_force_n,
                    compared.1
                );
            }
            for l in &s.layers {
                let mm = |m: Option<f64>| m.map_or("-".to_owned(), |m| format!("{:.1} mm", m * 1e3));
                let n = |f: Option<f64>| f.map_or("-".to_owned(), |f| format!("{f:.2} N"));
                let truth = format!(
                    "simulated {tissue} at {}: {}, {}",
                    l.speed_mps
                        .map_or("-".to_owned(), |v| format!("{:.1} mm/s", v * 1e3)),
                    mm(l.truth_depth_m),
                    n(l.truth_peak_force_n)
                );
                let felt = match (l.felt_depth_m, l.felt_peak_force_n, l.felt_drop_n) {
                    (Some(d), Some(f), Some(drop)) => {
                        format!("felt at {:.1} mm, peak {f:.2} N, drop {drop:.2} N", d * 1e3)
                    }
                    _ => l.status.to_owned(),
                };
                let _ = writeln!(t, "    layer {}: {felt} ({truth})", l.name);
            }
            if let Some(a) = &s.truth_along {
                let _ = writeln!(
                    t,
                    "    along the run against the simulated {tissue}: RMSE {:.3} N over {} ticks, largest error {:.3} N at {:.1} mm ({:.2} s)",
                    a.rmse_n,
                    a.ticks,
                    a.max_error_n,
                    a.max_error_depth_m * 1e3,
                    a.max_error_time_s
                );
                let list = |pops: &[crate::session::truth_along::Pop]| {
                    if pops.is_empty() {
                        "none".to_owned()
                    } else {
                        pops.iter()
                            .map(|p| format!("{:.2} N at {:.1} mm", p.drop_n, p.depth_m * 1e3))
                            .collect::<Vec<_>>()
                            .join(", ")
                    }
                };
                let _ = writeln!(
                    t,
                    "    pops the {tissue} does not have: {}; its pops not rendered: {}; held {} ticks, the rendered force went back and forth by at most {:.4} N over 0.2 s",
                    list(&a.false_pops),
                    list(&a.missed_pops),
                    a.held_ticks,
                    a.held_ripple_n
                );
            }
            if let Some(d) = s.max_depth_m {
                let _ = writeln!(
                    t,
                    "    deepest {:.1} mm, largest axial force {:.2} N",
                    d * 1e3,
                    s.max_model_force_n
                );
            }
            if let Some(r) = s.mean_friction_ratio {
                let _ = writeln!(
                    t,
                    "    friction/normal while sliding {r:.3}, largest normal force {:.2} N",
                    s.max_model_force_n
                );
            }
        }
        if let Some(r) = &self.recognizer {
            let rule = match (r.threshold, r.memory_s) {
                (Some(p), Some(m)) => {
                    let change = r.change_odds.map_or("no change test".to_owned(), |o| {
                        format!("a change of surface at {o:.0}:1")
                    });
                    let from = r
                        .window_weight_from
                        .as_ref()
                        .map_or(String::new(), |f| f.words(m));
                    let weight = r
                        .window_weight
                        .map_or(String::new(), |w| format!("each window weighing {w:.3}{from}, "));
                    format!(
                        "names a surface once its posterior reaches {p} ({weight}evidence of the last {}, {change})",
                        memory_in_words(m, r.window_s, r.window_m)
                    )
                }
                _ => "names a surface every window".to_owned(),
            };
            let _ = writeln!(
                t,
                "  recognizer: {} over {} {} every {} s, {}; {rule}",
                r.method,
                r.features,
                windows_in_words(r.window_s, r.window_m, r.friction_cutoff_m),
                r.hop_s,
                decided_after(r.decided_after_s)
            );
            if let Some(WindowWeightFrom::HeldOut(PosteriorWeight {
                held_out: Some(h), ..
            })) = &r.window_weight_from
            {
                let _ = writeln!(t, "    in training, anytime decisions {h}");
            }
        }
        if let Some(a) = self.recognition_accuracy {
            let named = self.recognition.iter().filter(|r| r.label.is_some()).count();
            let _ = writeln!(
                t,
                "  recognition: {:.1} % of {named} named decisions right ({} undecided)",
                a * 100.0,
                self.recognition.len() - named
            );
        }
        for (k, score) in self.attempts.iter().enumerate() {
            let number = (self.attempts.len() > 1).then_some(k + 1);
            let _ = writeln!(t, "{}", score_text(score, number));
        }
        if self.recognition_unread_windows > 0 {
            let _ = writeln!(
                t,
                "  {} windows could not be read and added no evidence (such as windows slid faster \
                 than the recognizer's spectra reach: train it with a higher --fastest-speed-mps)",
                self.recognition_unread_windows
            );
        }
        for SurfaceTiming { object, timing, .. } in &self.recognition_timing {
            let after = |v: Option<f64>| v.map_or("never".to_owned(), |v| format!("{v:.2} s"));
            let travel = timing
                .stable_right_after_m
                .map_or(String::new(), |m| format!(" and {:.1} mm", 1e3 * m));
            let _ = writeln!(
                t,
                "    {}: first named {}, named right for good {}{travel} after the stroke began ({} of {} named right)",
                object,
                after(timing.first_named_after_s),
                after(timing.stable_right_after_s),
                timing.right,
                timing.named
            );
        }
        for (p, rows) in &self.recorded {
            let _ = writeln!(t, "  recorded {rows} rows to {}", p.display());
        }
        match &self.frame {
            Ok(p) => {
                let _ = writeln!(t, "  frame {}", p.display());
            }
            Err(why) => {
                let _ = writeln!(t, "  no frame: {why}");
            }
        }
        let _ = writeln!(t, "  start to report {:.1} s", self.wall_s);
        t
    }
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> ReportError + '_ {
    move |source| ReportError::Io {
        path: path.to_owned(),
        source,
    }
}

/// The lines of the run summary that score an attempt (`number`ed when a session made several).
pub fn score_text(score: &super::score::Score, number: Option<usize>) -> String {
    let or_none = |v: Option<f64>, f: &dyn Fn(f64) -> String| v.map_or("—".to_owned(), f);
    format!(
        "  attempt {}{}: {}\n    overshoot {} (allowed {:.1} mm), peak force {:.2} N, time to target {}, \
         {} withdrawal{}, {} re-insertion{}, smoothness (SPARC) {}; layers given: {}",
        number.map_or_else(String::new, |n| format!("{n} ")),
        if score.passed { "PASSED" } else { "FAILED" },
        score.verdict,
        or_none(score.overshoot_m, &|m| format!("{:.1} mm", m * 1e3)),
        score.allowed_overshoot_m * 1e3,
        score.peak_force_n,
        or_none(score.time_to_target_s, &|s| format!("{s:.2} s")),
        score.withdrawals,
        if score.withdrawals == 1 { "" } else { "s" },
        score.reinsertions,
        if score.reinsertions == 1 { "" } else { "s" },
        or_none(score.smoothness_sparc, &|v| format!("{v:.2}")),
        if score.layers_given.is_empty() {
            "none".to_owned()
        } else {
            score.layers_given.join(", ")
        }
    )
}

/// Writes `summary.txt`, `report.json` and, if there are decisions, `timeline.csv`.
pub fn write_summary(dir: &Path, report: &SessionReport) -> Result<(), ReportError> {
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let text = dir.join("summary.txt");
    capture::write_atomically(&text, |w| w.write_all(report.to_text().as_bytes())).map_err(io(&text))?;
    let json = dir.join("report.json");
    capture::write_atomically(&json, |w| {
        serde_json::to_writer_pretty(&mut *w, report).map_err(std::io::Error::other)
    })
    .map_err(io(&json))?;
    if !report.recognition.is_empty() {
        let csv = dir.join("timeline.csv");
        capture::write_atomically(&csv, |w| {
            // An undecided row leaves `label` empty; `best` and `confidence` say where the
            // evidence stands.
            writeln!(w, "object,truth,time_s,label,best,confidence")?;
            for r in &report.recognition {
                writeln!(
                    w,
                    "{},{},{},{},{},{}",
                    r.object,
                    r.truth,
                    r.time_s,
                    r.label.as_deref().unwrap_or(""),
                    r.best,
                    r.confidence
                )?;
            }
            Ok(())
        })
        .map_err(io(&csv))?;
    }
    Ok(())
}

use std::io::Write;

/// What a window spans, in words: `window_s`, or `window_m` of travel (read through the play,
/// [`recognize::PlayedPath`]), and the friction's filter over travel if any.
pub fn windows_in_words(window_s: f64, window_m: Option<f64>, friction_cutoff_m: Option<f64>) -> String {
    let windows = match window_m {
        Some(m) => format!(
            "windows of {:.2} mm of travel read through a {:.2} mm play",
            m * 1e3,
            recognize::TRAVEL_PLAY_M * 1e3
        ),
        None => format!("windows of {window_s} s"),
    };
    match friction_cutoff_m {
        Some(m) => format!("{windows} (friction filtered over {:.2} mm of travel)", m * 1e3),
        None => windows,
    }
}

/// The span of evidence the posterior keeps, in words: `memory_s` of windows of `window_s`,
/// which over travel (windows of `window_m`) is a span of travel at any speed.
pub fn memory_in_words(memory_s: f64, window_s: f64, window_m: Option<f64>) -> String {
    match window_m {
        Some(m) => format!(
            "{:.1} mm of travel, {memory_s} s at {:.1} mm/s",
            memory_s * m / window_s * 1e3,
            m / window_s * 1e3
        ),
        None => format!("{memory_s} s"),
    }
}

/// When a window is decided, in words.
pub fn decided_after(seconds: f64) -> String {
    if seconds > 0.0 {
        format!("each decided {seconds:.2} s after its last sample")
    } else {
        "each decided at its last sample".to_owned()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_report_says_where_the_window_weight_came_from_and_at_what_memory() {
        let fitted = WindowWeightFrom::HeldOut(PosteriorWeight {
            weight: 0.057,
            hop_weight: 0.08,
            folds: 20,
            windows: 6258,
            brier: 0.151,
            hop_brier: 0.158,
            memory_s: 3.0,
            held_out: None,
        });
        assert_eq!(
            fitted.words(3.0),
            " as fitted on held-out recordings rather than hop / window's 0.080"
        );
        assert_eq!(
            fitted.words(6.0),
            " as fitted on held-out recordings over a memory of 3 s, not this one, rather than hop / window's 0.080"
        );
        assert_eq!(WindowWeightFrom::HopWindow.words(6.0), " (hop / window)");
    }
}

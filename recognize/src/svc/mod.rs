//! Multi-class support vector classification as libsvm does it (Sinapov et al. used WEKA's SMO
//! with a degree-2 polynomial kernel): one C-SVC per pair of classes, prediction by their
//! votes, and class probabilities by pairwise coupling (Wu, Lin & Weng 2004, method 2) of each
//! pair's Platt sigmoid (Lin, Lin & Weng 2007's Newton fit) on cross-validated decision values.
//!
//! **Solver.** The C-SVC dual `min ½ αᵀQα − eᵀα, yᵀα = 0, 0 ≤ α ≤ C`, `Q_ij = y_i y_j K_ij`, is
//! solved by SMO with the second-order working-set selection of Fan, Chen & Lin (2005), the
//! pair update and the bias (`ρ`, averaged over free vectors) of libsvm's `Solver`, so decision
//! values agree with libsvm (and scikit-learn's `SVC`) to the stopping tolerance. Each pair is
//! solved by the svm crate's one SMO ([`svm::solve_svc`]: libsvm's memory layout, its
//! shrinking, kernel rows computed as the solver first asks for them and cached).
//! The pairs' machines and their probability folds are independent solves, run on all cores.
//!
//! **Probabilities.** For each pair, decision values from a 5-fold cross-validation on that
//! pair's training vectors (folds from a seeded shuffle, as libsvm's) are fitted by Platt's
//! sigmoid; at query time the sigmoids give `r_ij ≈ P(i | i or j, x)`, and method 2 finds the
//! `p` minimising `Σ_i Σ_{j≠i} (r_ji p_i − r_ij p_j)²` with `Σ p = 1`. libsvm stops that
//! fixed-point iteration at a loose tolerance (0.005/k); we iterate to 1e-12 so that the result
//! is the minimiser itself, which is what the reference fixture computes by a direct solve.

use crate::RecognizeError;
use crate::{DataError, SettingError, SolverError, UsageError};
use serde::{Deserialize, Serialize};

use crate::vectors;
use crate::vectors::FeatureScaling;
use capture::rng::SplitMix64;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
use svm::{Kernel, SelectionCurvature, SmoSettings, SmoSolution};

mod c_search;
mod probability;

/// Memory for one solve's cached kernel rows (scikit-learn's `cache_size` is 200 MB); with
/// every core solving, that many times this is held. A pair of up to 4,096 training vectors
/// keeps every row.
const CACHE_BYTES: usize = 128 << 20;

pub(crate) use c_search::repeat_weight;
pub use c_search::{C_GRID, CSearch, CvPoint, select_c_observed, select_c_sparse};
#[cfg(test)]
use c_search::{cross_validated_accuracy, select_c};
#[cfg(test)]
use probability::pairwise_coupling;
use probability::{CouplingScratch, pairwise_coupling_into};
pub use probability::{sigmoid_predict, sigmoid_train};

/// Hyperparameters, checked when fitting.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SvcParams {
    /// Box constraint C > 0.
    pub c: f64,
    /// The kernel (libsvm's parameterisation).
    pub kernel: Kernel,
    /// Stopping tolerance on the maximal KKT violation (libsvm's ε, default 1e-3).
    pub tolerance: f64,
    /// Feature scaling learned from the training set.
    pub scaling: FeatureScaling,
    /// Fit Platt sigmoids for class probabilities (5 more fits per pair).
    pub probability: bool,
    /// Seed of the probability cross-validation's folds.
    pub seed: u64,
    /// Most SMO iterations per binary machine; 0 for the solver's own budget (at least 10⁷).
    /// Recognizer files written before it existed read as 0.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub max_iterations: usize,
    /// Wall-clock budget of each binary machine's solve, counted from the instant given: a
    /// fit still running past it ends with the solver's [`svm::SvmError::Budget`]. For a caller
    /// that must end by a time (the default search's candidates); not kept in files.
    #[serde(skip)]
    pub time_budget: Option<(Instant, Duration)>,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

/// What a fit or a C search reports while it runs: the library prints nothing itself, so a
/// caller that wants a progress bar or warnings passes a [`Progress`] that shows them.
#[derive(Debug)]
pub enum FitEvent {
    /// A step of `total` units began (units of different steps are alike in cost only roughly).
    Step {
        /// What the step does.
        what: &'static str,
        /// Its units.
        total: usize,
    },
    /// One more unit of a step done.
    Advance,
    /// A candidate of a C search could not be fitted (the solver did not converge, or failed
    /// numerically) and was left out; the search goes on with the others.
    SkippedC {
        /// The candidate.
        c: f64,
        /// Why its fit failed.
        error: RecognizeError,
    },
    /// A line for the user, e.g. a [`FitEvent::SkippedC`] put in the caller's terms.
    Warning(String),
}

/// Receives [`FitEvent`]s, possibly from several threads at once.
pub type Progress<'a> = &'a (dyn Fn(FitEvent) + Sync);

/// A [`Progress`] that drops every event.
pub fn no_progress(_: FitEvent) {}

impl Default for SvcParams {
    /// C = 10⁴, `(a·b / 125 + 1)²` (degree 2, γ = 1/125 for Sinapov's 125-cell histograms),
    /// tolerance 1e-3, min–max scaling, probabilities on, seed 0.
    ///
    /// C: two surfaces' min–max-scaled histograms are (nearly always) separable by this kernel,
    /// so a large C gives the hard-margin machine. With C = 1 every vector of a pair ends at the
    /// bound; the machine still votes well, but its cross-validated decision values are
    /// anti-correlated with the labels (leaving a vector out tips the balance of the bounded
    /// rest), Platt's sigmoid fits the wrong sign and the coupled probabilities are useless.
    fn default() -> Self {
        Self {
            c: 1e4,
            kernel: Kernel::Polynomial {
                gamma: 1.0 / 125.0,
                coef0: 1.0,
                degree: 2,
            },
            tolerance: 1e-3,
            scaling: FeatureScaling::MinMax,
            probability: true,
            seed: 0,
            max_iterations: 0,
            time_budget: None,
        }
    }
}

impl SvcParams {
    /// The SMO core's settings: libsvm's C-SVC solver (shrinking, its selection rule, its
    /// iteration budget), stopping at [`SvcParams::tolerance`].
    fn smo_settings(&self) -> Result<SmoSettings, RecognizeError> {
        self.check()?;
        let settings = SmoSettings::builder()
            .c(self.c)
            .stop(self.tolerance)
            .selection(SelectionCurvature::NonPositiveToTau)
            .shrinking(true)
            .max_iterations(self.max_iterations);
        match self.time_budget {
            Some((started, budget)) => settings.time_budget(started, budget),
            None => settings,
        }
        .build()
        .map_err(|e| match e {
            svm::SvmError::InvalidHyperparameter { name, value, reason } => {
                RecognizeError::Setting(SettingError::Parameter {
                    of: "SVC parameter",
                    name,
                    value,
                    reason,
                })
            }
            _ => RecognizeError::Setting(SettingError::Parameter {
                of: "SVC parameter",
                name: "c",
                value: self.c,
                reason: "positive and finite",
            }),
        })
    }

    fn check(&self) -> Result<(), RecognizeError> {
        let bad = |name, value, reason| {
            Err(RecognizeError::Setting(SettingError::Parameter {
                of: "SVC parameter",
                name,
                value,
                reason,
            }))
        };
        if !(self.c.is_finite() && self.c > 0.0) {
            return bad("c", self.c, "positive and finite");
        }
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return bad("tolerance", self.tolerance, "positive and finite");
        }
        match self.kernel {
            Kernel::Rbf { gamma } | Kernel::Polynomial { gamma, .. }
                if !(gamma.is_finite() && gamma > 0.0) =>
            {
                bad("gamma", gamma, "positive and finite")
            }
            Kernel::Polynomial { degree: 0, .. } => bad("degree", 0.0, "at least 1"),
            Kernel::Polynomial { coef0, .. } if !coef0.is_finite() => bad("coef0", coef0, "finite"),
            _ => Ok(()),
        }
    }
}

/// Labelled training vectors exactly as an SVC is fitted on them (scaled, in order), with the
/// cross-validation group of each: what another SVM library must be given to be compared with
/// this one (see `recognize/benches/svc.rs`).
#[derive(Debug, Clone, PartialEq)]
pub struct TrainingVectors {
    /// The classes, in the recognizer's order; labels index them.
    pub classes: Vec<String>,
    /// The vectors.
    pub x: Vec<Vec<f64>>,
    /// Their class indices.
    pub y: Vec<usize>,
    /// Their cross-validation groups (the run or trial of the capture each came from).
    pub groups: Vec<u64>,
}

/// Folds of the cross-validation behind each pair's sigmoid (libsvm's).
const PROBABILITY_FOLDS: usize = 5;

/// One binary C-SVC: `f(x) = Σ coef_t K(x_t, x) − ρ`, positive for the pair's first class.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BinarySvc {
    /// The pair `(i, j)`, `i < j`; positive decisions vote for `i`.
    pub classes: (usize, usize),
    /// Support vectors: (index into the classifier's points, `y_t α_t`: positive for class
    /// `i`, negative for `j`).
    pub support: Vec<(usize, f64)>,
    /// Bias ρ.
    pub rho: f64,
    /// Platt sigmoid `P(i | x) = 1 / (1 + exp(A f + B))`, if fitted.
    pub sigmoid: Option<(f64, f64)>,
}

/// A fitted one-vs-one multi-class SVC.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Svc {
    params: SvcParams,
    classes: usize,
    dim: usize,
    /// Per feature `(offset, factor)`: scaled = (x − offset)·factor.
    scale: Vec<(f64, f64)>,
    /// Scaled support vectors (the training points some machine uses; files written before
    /// only these were kept hold every training point), row-major.
    points: Vec<f64>,
    /// The `k(k − 1)/2` binary machines in libsvm's order: (0,1), (0,2), …, (1,2), …
    machines: Vec<BinarySvc>,
}

impl Svc {
    /// This classifier with the Platt sigmoids of `other`, a fit with probabilities of the same
    /// classes (a refit on part of its data, whose own sigmoids would cost five more fits a
    /// pair); `None` when `other` has none or other pairs.
    pub(crate) fn with_sigmoids_of(mut self, other: &Svc) -> Option<Self> {
        if other.classes != self.classes
            || !other.params.probability
            || other.machines.len() != self.machines.len()
        {
            return None;
        }
        for (m, o) in self.machines.iter_mut().zip(&other.machines) {
            if m.classes != o.classes || o.sigmoid.is_none() {
                return None;
            }
            m.sigmoid = o.sigmoid;
        }
        self.params.probability = true;
        Some(self)
    }

    /// Fits on `features` with `labels` in `0..classes`; every class needs a vector.
    pub fn fit<V: AsRef<[f64]>>(
        params: SvcParams,
        features: &[V],
        labels: &[usize],
        classes: usize,
    ) -> Result<Self, RecognizeError> {
        Self::fit_pairs(params, features, labels, classes, &|| {})
    }

    /// [`Svc::fit`], reporting to `progress` one [`FitEvent::Step`] whose units are the binary
    /// machines and, with probabilities, each machine's sigmoid folds.
    pub fn fit_observed<V: AsRef<[f64]>>(
        params: SvcParams,
        features: &[V],
        labels: &[usize],
        classes: usize,
        progress: Progress<'_>,
    ) -> Result<Self, RecognizeError> {
        let pairs = classes * classes.saturating_sub(1) / 2;
        let per_pair = if params.probability {
            1 + PROBABILITY_FOLDS
        } else {
            1
        };
        progress(FitEvent::Step {
            what: if params.probability {
                "fitting machines and sigmoids"
            } else {
                "fitting machines"
            },
            total: pairs * per_pair,
        });
        Self::fit_pairs(params, features, labels, classes, &|| progress(FitEvent::Advance))
    }

    /// [`Svc::fit`], calling `tick` after each binary machine and each sigmoid fold.
    ///
    /// Every solve (each pair's machine and, with probabilities, its folds' machines) is an
    /// independent task run on all cores; the folds' shuffles are drawn in pair order first, so
    /// the result does not depend on the order the tasks finish in.
    pub(super) fn fit_pairs<V: AsRef<[f64]>>(
        params: SvcParams,
        features: &[V],
        labels: &[usize],
        classes: usize,
        tick: &(dyn Fn() + Sync),
    ) -> Result<Self, RecognizeError> {
        let settings = params.smo_settings()?;
        if features.is_empty() || features.len() != labels.len() {
            return Err(RecognizeError::Usage(UsageError::Counts {
                features: features.len(),
                labels: labels.len(),
            }));
        }
        let dim = features[0].as_ref().len();
        vectors::check_labelled(features, labels, dim, classes)?;
        if let Some(class) = (0..classes).find(|c| !labels.contains(c)) {
            return Err(RecognizeError::Data(DataError::EmptyClass { class }));
        }
        let scale = params.scaling.fit(features, dim);
        let points = vectors::scaled_rows(features, &scale);
        let pairs: Vec<Pair> = (0..classes)
            .flat_map(|i| (i + 1..classes).map(move |j| (i, j)))
            .map(|(i, j)| {
                let members: Vec<usize> = (0..labels.len())
                    .filter(|&t| labels[t] == i || labels[t] == j)
                    .collect();
                let y = members
                    .iter()
                    .map(|&t| if labels[t] == i { 1.0 } else { -1.0 })
                    .collect();
                Pair {
                    classes: (i, j),
                    members,
                    y,
                    order: Vec::new(),
                }
            })
            .collect();
        let mut pairs = pairs;
        if params.probability {
            let mut rng = SplitMix64::new(params.seed);
            for pair in &mut pairs {
                // A Fisher–Yates shuffle, then folds of consecutive positions (libsvm's layout).
                let n = pair.members.len();
                pair.order = (0..n).collect();
                for a in (1..n).rev() {
                    pair.order.swap(a, rng.below(a + 1));
                }
            }
        }
        let folds = if params.probability { PROBABILITY_FOLDS } else { 0 };
        let tasks: Vec<(usize, Option<usize>)> = (0..pairs.len())
            .flat_map(|p| std::iter::once((p, None)).chain((0..folds).map(move |f| (p, Some(f)))))
            .collect();
        // Once a solve has failed the fit fails: the tasks not yet started are not run.
        let failed = AtomicBool::new(false);
        let mut outcomes: Vec<Option<Result<Solved, RecognizeError>>> = tasks
            .par_iter()
            .map(|&(p, fold)| {
                if failed.load(Ordering::Relaxed) {
                    return None;
                }
                let pair = &pairs[p];
                let solved = match fold {
                    None => pair.solve(&points, dim, &params, &settings).map(Solved::Machine),
                    Some(f) => pair
                        .fold_decisions(f, &points, dim, &params, &settings)
                        .map(Solved::Fold),
                };
                if solved.is_err() {
                    failed.store(true, Ordering::Relaxed);
                }
                tick();
                Some(solved)
            })
            .collect();
        // The first failure in pair order is reported (one of them, if several pairs fail).
        let mut machines: Vec<BinarySvc> = Vec::with_capacity(pairs.len());
        let mut decisions: Vec<Vec<f64>> = pairs.iter().map(|p| vec![0.0; p.members.len()]).collect();
        let first_failure = outcomes.iter().position(|o| matches!(o, Some(Err(_))));
        if let Some(Some(Err(e))) = first_failure.map(|at| outcomes.swap_remove(at)) {
            return Err(e);
        }
        for (outcome, &(p, _)) in outcomes.into_iter().zip(&tasks) {
            match outcome {
                Some(Ok(Solved::Machine(machine))) => machines.push(machine),
                Some(Ok(Solved::Fold(fold))) => {
                    for (s, d) in fold {
                        decisions[p][s] = d;
                    }
                }
                // Not run: only after a failure, which returned above.
                _ => return Err(pairs[p].not_converged(&settings, &params, f64::INFINITY)),
            }
        }
        if params.probability {
            for (machine, (pair, dec)) in machines.iter_mut().zip(pairs.iter().zip(&decisions)) {
                machine.sigmoid = Some(sigmoid_train(dec, &pair.y));
            }
        }
        let points = keep_support(&points, dim, &mut machines);
        Ok(Self {
            params,
            classes,
            dim,
            scale,
            points,
            machines,
        })
    }

    /// Number of classes.
    pub fn classes(&self) -> usize {
        self.classes
    }

    /// The hyperparameters it was fitted with.
    pub fn params(&self) -> &SvcParams {
        &self.params
    }

    /// The binary machines, in libsvm's pair order.
    pub fn machines(&self) -> &[BinarySvc] {
        &self.machines
    }

    /// Whether some machine has a multiplier at its bound C. When none has, the machines are
    /// also a solution for every larger C: the solver's stopping test reads the bound only
    /// through the multipliers that sit on it (see [`select_c`]).
    pub fn any_multiplier_at_bound(&self) -> bool {
        // The solver clips a multiplier to exactly C, so equality is the test.
        self.machines
            .iter()
            .any(|m| m.support.iter().any(|&(_, coef)| coef.abs() >= self.params.c))
    }

    /// Dimension of the feature vectors.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Checks the shapes and values of a classifier read from a file: `Err((field, reason))`.
    pub fn check_shape(&self) -> Result<(), (&'static str, String)> {
        if let Err(e) = self.params.check() {
            return Err(("params", e.to_string()));
        }
        if self.dim == 0 || self.scale.len() != self.dim || !self.points.len().is_multiple_of(self.dim) {
            return Err(("points", format!("not whole vectors of dimension {}", self.dim)));
        }
        let n = self.points.len() / self.dim;
        let pairs: Vec<(usize, usize)> = (0..self.classes)
            .flat_map(|i| (i + 1..self.classes).map(move |j| (i, j)))
            .collect();
        if self.machines.len() != pairs.len()
            || self.machines.iter().zip(&pairs).any(|(m, p)| m.classes != *p)
        {
            return Err((
                "machines",
                format!(
                    "expected the {} pairs of {} classes in order",
                    pairs.len(),
                    self.classes
                ),
            ));
        }
        for m in &self.machines {
            if m.support.iter().any(|&(t, c)| t >= n || !c.is_finite()) || !m.rho.is_finite() {
                return Err((
                    "machines",
                    format!(
                        "pair {:?}: a support index past {n} or a non-finite value",
                        m.classes
                    ),
                ));
            }
            if m.sigmoid.is_some_and(|(a, b)| !(a.is_finite() && b.is_finite())) {
                return Err(("machines", format!("pair {:?}: non-finite sigmoid", m.classes)));
            }
            // Probabilities couple every pair's sigmoid: one missing would make every query
            // fail where the file promised probabilities.
            if m.sigmoid.is_some() != self.params.probability {
                return Err((
                    "machines",
                    format!(
                        "pair {:?}: {} sigmoid where params.probability is {}",
                        m.classes,
                        if m.sigmoid.is_some() { "a" } else { "no" },
                        self.params.probability
                    ),
                ));
            }
        }
        let finite = self.points.iter().all(|v| v.is_finite())
            && self.scale.iter().all(|(o, s)| o.is_finite() && s.is_finite());
        if !finite {
            return Err(("points", "contains a non-finite value".into()));
        }
        Ok(())
    }

    /// Decision values of every pair, in [`Svc::machines`] order (scikit-learn's
    /// `decision_function` with `decision_function_shape='ovo'`).
    pub fn decision_values(&self, query: &[f64]) -> Result<Vec<f64>, RecognizeError> {
        let mut scratch = self.scratch();
        self.decision_values_into(query, &mut scratch)?;
        Ok(scratch.decision)
    }

    /// Buffers for [`Svc::predict_proba_into`], made once for this machine.
    pub fn scratch(&self) -> SvcScratch {
        let mut support: Vec<usize> = self
            .machines
            .iter()
            .flat_map(|m| m.support.iter().map(|&(t, _)| t))
            .collect();
        support.sort_unstable();
        support.dedup();
        SvcScratch {
            kernel: vec![0.0; self.points.len() / self.dim.max(1)],
            support,
            query: vec![0.0; self.dim],
            decision: vec![0.0; self.machines.len()],
            pairwise: vec![0.0; self.classes * self.classes],
            coupling: CouplingScratch::new(self.classes),
        }
    }

    /// [`Svc::decision_values`] into `scratch.decision`.
    fn decision_values_into(&self, query: &[f64], scratch: &mut SvcScratch) -> Result<(), RecognizeError> {
        vectors::check_query(query, self.dim)?;
        vectors::check_buffer("SVC scratch", scratch.query.len(), self.dim)?;
        vectors::check_buffer("SVC scratch", scratch.decision.len(), self.machines.len())?;
        for (q, v) in scratch.query.iter_mut().zip(vectors::scaled(query, &self.scale)) {
            *q = v;
        }
        let dim = self.dim;
        vectors::check_buffer(
            "SVC scratch",
            scratch.kernel.len(),
            self.points.len() / dim.max(1),
        )?;
        // A point supports up to `classes − 1` pairs: its kernel value is computed once and
        // read by each of them (the same value, so the sums are those of one pass per pair).
        for &t in &scratch.support {
            scratch.kernel[t] = self
                .params
                .kernel
                .eval(&self.points[t * dim..(t + 1) * dim], &scratch.query);
        }
        for (d, m) in scratch.decision.iter_mut().zip(&self.machines) {
            *d = m
                .support
                .iter()
                .map(|&(t, coef)| coef * scratch.kernel[t])
                .sum::<f64>()
                - m.rho;
        }
        Ok(())
    }

    /// The class with most pairwise votes; ties to the lowest class (libsvm's rule).
    pub fn predict(&self, query: &[f64]) -> Result<usize, RecognizeError> {
        let dec = self.decision_values(query)?;
        let mut votes = vec![0usize; self.classes];
        for (m, d) in self.machines.iter().zip(&dec) {
            votes[if *d > 0.0 { m.classes.0 } else { m.classes.1 }] += 1;
        }
        let best = votes.iter().copied().max().unwrap_or(0);
        Ok(votes.iter().position(|&v| v == best).unwrap_or(0))
    }

    /// Class probabilities by pairwise coupling of the pairs' sigmoids.
    pub fn predict_proba(&self, query: &[f64]) -> Result<Vec<f64>, RecognizeError> {
        let mut scratch = self.scratch();
        let mut p = vec![0.0; self.classes];
        self.predict_proba_into(query, &mut scratch, &mut p)?;
        Ok(p)
    }

    /// [`Svc::predict_proba`] into `p` (one per class) on `scratch` (from [`Svc::scratch`]),
    /// allocating nothing: for a thread that must not.
    pub fn predict_proba_into(
        &self,
        query: &[f64],
        scratch: &mut SvcScratch,
        p: &mut [f64],
    ) -> Result<(), RecognizeError> {
        vectors::check_buffer("class probability", p.len(), self.classes)?;
        vectors::check_buffer("SVC scratch", scratch.pairwise.len(), self.classes * self.classes)?;
        self.decision_values_into(query, scratch)?;
        let k = self.classes;
        let SvcScratch {
            decision,
            pairwise: r,
            coupling,
            ..
        } = scratch;
        r.fill(0.0);
        for (m, d) in self.machines.iter().zip(decision.iter()) {
            let (a, b) = m
                .sigmoid
                .ok_or(RecognizeError::Setting(SettingError::NoProbability))?;
            let p = sigmoid_predict(*d, a, b).clamp(1e-7, 1.0 - 1e-7);
            r[m.classes.0 * k + m.classes.1] = p;
            r[m.classes.1 * k + m.classes.0] = 1.0 - p;
        }
        pairwise_coupling_into(r, coupling, p);
        Ok(())
    }
}

/// The buffers one [`Svc`] needs to classify a query without allocating ([`Svc::scratch`]).
#[derive(Debug, Clone)]
pub struct SvcScratch {
    /// Every point that supports a pair, once, and its kernel value against the query (by
    /// point index).
    support: Vec<usize>,
    kernel: Vec<f64>,
    query: Vec<f64>,
    decision: Vec<f64>,
    /// The pairs' probabilities, `classes × classes` row-major.
    pairwise: Vec<f64>,
    coupling: CouplingScratch,
}

/// One pair of classes: its training vectors and, with probabilities, their folds' order.
struct Pair {
    /// `(i, j)`, `i < j`.
    classes: (usize, usize),
    /// Indices of the pair's training points.
    members: Vec<usize>,
    /// +1 for class `i`, −1 for class `j`, per member.
    y: Vec<f64>,
    /// The members' positions shuffled; fold `f` holds a consecutive fifth of them.
    order: Vec<usize>,
}

/// What one task of [`Svc::fit_pairs`] produced.
enum Solved {
    /// A pair's machine (no sigmoid yet).
    Machine(BinarySvc),
    /// A fold's held-out members (positions in the pair) and their decision values.
    Fold(Vec<(usize, f64)>),
}

impl Pair {
    fn not_converged(&self, settings: &SmoSettings, params: &SvcParams, violation: f64) -> RecognizeError {
        RecognizeError::Solver(SolverError::NotConverged {
            iterations: settings.iteration_budget(self.members.len()),
            c: params.c,
            first: self.classes.0,
            second: self.classes.1,
            violation,
            stop: params.tolerance,
        })
    }

    /// The pair's own error for the solver's: at the iteration limit, which classes and C, and
    /// the KKT violation it reached.
    fn failed(&self, settings: &SmoSettings, params: &SvcParams, error: svm::SvmError) -> RecognizeError {
        match error {
            svm::SvmError::NotConverged { gap, .. } => self.not_converged(settings, params, gap),
            other => other.into(),
        }
    }

    /// The pair's machine on all its members.
    fn solve(
        &self,
        points: &[f64],
        dim: usize,
        params: &SvcParams,
        settings: &SmoSettings,
    ) -> Result<BinarySvc, RecognizeError> {
        let SmoSolution { alpha, rho, .. } = solve(&self.members, &self.y, points, dim, params, settings)
            .map_err(|e| self.failed(settings, params, e))?;
        let support = self
            .members
            .iter()
            .zip(alpha.iter().zip(&self.y))
            .filter(|(_, (a, _))| **a > 0.0)
            .map(|(&t, (a, yt))| (t, a * yt))
            .collect();
        Ok(BinarySvc {
            classes: self.classes,
            support,
            rho,
            sigmoid: None,
        })
    }

    /// Decision values of fold `fold`'s members from a machine trained on the other folds.
    fn fold_decisions(
        &self,
        fold: usize,
        points: &[f64],
        dim: usize,
        params: &SvcParams,
        settings: &SmoSettings,
    ) -> Result<Vec<(usize, f64)>, RecognizeError> {
        let n = self.members.len();
        let (begin, end) = (fold * n / PROBABILITY_FOLDS, (fold + 1) * n / PROBABILITY_FOLDS);
        let test = &self.order[begin..end];
        let train: Vec<usize> = self.order[..begin]
            .iter()
            .chain(&self.order[end..])
            .copied()
            .collect();
        let positive = train.iter().filter(|&&t| self.y[t] > 0.0).count();
        let negative = train.len() - positive;
        // One class only in training: libsvm's fallback, a constant decision of that sign.
        if positive == 0 || negative == 0 {
            let v = if positive > 0 {
                1.0
            } else if negative > 0 {
                -1.0
            } else {
                0.0
            };
            return Ok(test.iter().map(|&t| (t, v)).collect());
        }
        let ty: Vec<f64> = train.iter().map(|&t| self.y[t]).collect();
        let subset: Vec<usize> = train.iter().map(|&t| self.members[t]).collect();
        let SmoSolution { alpha, rho, .. } = solve(&subset, &ty, points, dim, params, settings)
            .map_err(|e| self.failed(settings, params, e))?;
        let support: Vec<(&[f64], f64)> = subset
            .iter()
            .zip(alpha.iter().zip(&ty))
            .filter(|(_, (a, _))| **a > 0.0)
            .map(|(&p, (a, ys))| (&points[p * dim..(p + 1) * dim], a * ys))
            .collect();
        Ok(test
            .iter()
            .map(|&t| {
                let m = self.members[t];
                let x = &points[m * dim..(m + 1) * dim];
                let f = support
                    .iter()
                    .map(|&(sv, coef)| coef * params.kernel.eval(sv, x))
                    .sum::<f64>();
                (t, f - rho)
            })
            .collect())
    }
}

/// The binary C-SVC on the points `subset` with labels `y` (±1), with `settings`' C,
/// tolerance and iteration budget.
fn solve(
    subset: &[usize],
    y: &[f64],
    points: &[f64],
    dim: usize,
    params: &SvcParams,
    settings: &SmoSettings,
) -> Result<SmoSolution, svm::SvmError> {
    svm::solve_svc(params.kernel, points, dim, subset, y, settings, CACHE_BYTES)
}

/// The training points some machine uses, in training order, with every machine's support
/// indices renumbered to them: a point no machine uses adds nothing to any decision, so a
/// file need not carry it. The decisions are those over all the points, to the bit: each
/// machine sums the same terms in the same order.
fn keep_support(points: &[f64], dim: usize, machines: &mut [BinarySvc]) -> Vec<f64> {
    let n = points.len() / dim.max(1);
    let mut kept_as = vec![usize::MAX; n];
    for m in machines.iter() {
        for &(t, _) in &m.support {
            kept_as[t] = 0;
        }
    }
    let mut kept = Vec::new();
    let mut next = 0;
    for (t, k) in kept_as.iter_mut().enumerate() {
        if *k == 0 {
            *k = next;
            next += 1;
            kept.extend_from_slice(&points[t * dim..(t + 1) * dim]);
        }
    }
    for m in machines.iter_mut() {
        for (t, _) in &mut m.support {
            *t = kept_as[*t];
        }
    }
    kept
}

#[cfg(test)]
mod tests;

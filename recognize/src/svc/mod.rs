//! Multi-class support vector classification as libsvm does it (Sinapov et al. used WEKA's SMO
//! with a degree-2 polynomial kernel): one C-SVC per pair of classes, prediction by their
//! votes, and class probabilities by pairwise coupling (Wu, Lin & Weng 2004, method 2) of each
//! pair's Platt sigmoid (Lin, Lin & Weng 2007's Newton fit) on cross-validated decision values.
//!
//! **Solver.** The C-SVC dual `min ½ αᵀQα − eᵀα, yᵀα = 0, 0 ≤ α ≤ C`, `Q_ij = y_i y_j K_ij`, is
//! solved by SMO with the second-order working-set selection of Fan, Chen & Lin (2005), the
//! pair update and the bias (`ρ`, averaged over free vectors) of libsvm's `Solver`, so decision
//! values agree with libsvm (and scikit-learn's `SVC`) to the stopping tolerance. The solver is
//! [`svm::solve_smo`], the core the ε-SVR uses too, here on a precomputed Gram matrix without
//! shrinking: a pair of surface classes has tens of training vectors, whose whole Gram matrix
//! is smaller than one cached SVR row.
//!
//! **Probabilities.** For each pair, decision values from a 5-fold cross-validation on that
//! pair's training vectors (folds from a seeded shuffle, as libsvm's) are fitted by Platt's
//! sigmoid; at query time the sigmoids give `r_ij ≈ P(i | i or j, x)`, and method 2 finds the
//! `p` minimising `Σ_i Σ_{j≠i} (r_ji p_i − r_ij p_j)²` with `Σ p = 1`. libsvm stops that
//! fixed-point iteration at a loose tolerance (0.005/k); we iterate to 1e-12 so that the result
//! is the minimiser itself, which is what the reference fixture computes by a direct solve.

use crate::RecognizeError;
use serde::{Deserialize, Serialize};

use crate::vectors;
use crate::vectors::FeatureScaling;
use capture::rng::SplitMix64;
use svm::{GramRows, Kernel, SelectionCurvature, SmoSettings, SmoSolution};

mod c_search;
mod probability;

pub use c_search::{C_GRID, CSearch, CvPoint, cross_validated_accuracy, select_c, select_c_observed};
pub use probability::{pairwise_coupling, sigmoid_predict, sigmoid_train};

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
        }
    }
}

impl SvcParams {
    /// The SMO core's settings: libsvm's C-SVC solver (no shrinking, its selection rule, its
    /// iteration budget), stopping at [`SvcParams::tolerance`].
    fn smo_settings(&self) -> Result<SmoSettings, RecognizeError> {
        self.check()?;
        SmoSettings::builder()
            .c(self.c)
            .stop(self.tolerance)
            .selection(SelectionCurvature::NonPositiveToTau)
            .max_iterations(self.max_iterations)
            .build()
            .map_err(|e| match e {
                svm::SvmError::InvalidHyperparameter { name, value, reason } => RecognizeError::Parameter {
                    of: "SVC parameter",
                    name,
                    value,
                    reason,
                },
                _ => RecognizeError::Parameter {
                    of: "SVC parameter",
                    name: "c",
                    value: self.c,
                    reason: "positive and finite",
                },
            })
    }

    fn check(&self) -> Result<(), RecognizeError> {
        let bad = |name, value, reason| {
            Err(RecognizeError::Parameter {
                of: "SVC parameter",
                name,
                value,
                reason,
            })
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

/// Folds of the cross-validation behind each pair's sigmoid (libsvm's).
const PROBABILITY_FOLDS: usize = 5;

/// One binary C-SVC: `f(x) = Σ coef_t K(x_t, x) − ρ`, positive for the pair's first class.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BinarySvc {
    /// The pair `(i, j)`, `i < j`; positive decisions vote for `i`.
    pub classes: (usize, usize),
    /// Support vectors: (training point index, `y_t α_t`).
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
    /// Scaled training points, row-major.
    points: Vec<f64>,
    /// The `k(k − 1)/2` binary machines in libsvm's order: (0,1), (0,2), …, (1,2), …
    machines: Vec<BinarySvc>,
}

impl Svc {
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
    pub(super) fn fit_pairs<V: AsRef<[f64]>>(
        params: SvcParams,
        features: &[V],
        labels: &[usize],
        classes: usize,
        tick: &dyn Fn(),
    ) -> Result<Self, RecognizeError> {
        let settings = params.smo_settings()?;
        if features.is_empty() || features.len() != labels.len() {
            return Err(RecognizeError::Counts {
                features: features.len(),
                labels: labels.len(),
            });
        }
        let dim = features[0].as_ref().len();
        vectors::check_labelled(features, labels, dim, classes)?;
        if let Some(class) = (0..classes).find(|c| !labels.contains(c)) {
            return Err(RecognizeError::EmptyClass { class });
        }
        let scale = params.scaling.fit(features, dim);
        let points = vectors::scaled_rows(features, &scale);
        let row = |t: usize| &points[t * dim..(t + 1) * dim];
        let mut rng = SplitMix64::new(params.seed);
        let mut machines = Vec::with_capacity(classes * classes.saturating_sub(1) / 2);
        for i in 0..classes {
            for j in i + 1..classes {
                let members: Vec<usize> = (0..labels.len())
                    .filter(|&t| labels[t] == i || labels[t] == j)
                    .collect();
                let y: Vec<f64> = members
                    .iter()
                    .map(|&t| if labels[t] == i { 1.0 } else { -1.0 })
                    .collect();
                let gram = |subset: &[usize]| -> Vec<f64> {
                    let n = subset.len();
                    let mut k = vec![0.0; n * n];
                    for a in 0..n {
                        for b in a..n {
                            let v = params
                                .kernel
                                .eval(row(members[subset[a]]), row(members[subset[b]]));
                            k[a * n + b] = v;
                            k[b * n + a] = v;
                        }
                    }
                    k
                };
                let all: Vec<usize> = (0..members.len()).collect();
                let not_converged = || RecognizeError::NotConverged {
                    iterations: settings.iteration_budget(members.len()),
                    c: params.c,
                    first: i,
                    second: j,
                };
                let SmoSolution { alpha, rho, .. } =
                    solve(&gram(&all), &y, &settings).ok_or_else(not_converged)?;
                tick();
                let support = members
                    .iter()
                    .zip(alpha.iter().zip(&y))
                    .filter(|(_, (a, _))| **a > 0.0)
                    .map(|(&t, (a, yt))| (t, a * yt))
                    .collect();
                let sigmoid = if params.probability {
                    let dec =
                        cross_validated_decisions(&members, &y, &params, &settings, &row, &mut rng, tick)
                            .ok_or_else(not_converged)?;
                    Some(sigmoid_train(&dec, &y))
                } else {
                    None
                };
                machines.push(BinarySvc {
                    classes: (i, j),
                    support,
                    rho,
                    sigmoid,
                });
            }
        }
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
        }
        let finite = self.points.iter().all(|v| v.is_finite())
            && self.scale.iter().all(|(o, s)| o.is_finite() && s.is_finite());
        if !finite {
            return Err(("points", "contains a non-finite value".into()));
        }
        Ok(())
    }

    fn scaled(&self, query: &[f64]) -> Result<Vec<f64>, RecognizeError> {
        vectors::check_query(query, self.dim)?;
        Ok(vectors::scaled(query, &self.scale).collect())
    }

    /// Decision values of every pair, in [`Svc::machines`] order (scikit-learn's
    /// `decision_function` with `decision_function_shape='ovo'`).
    pub fn decision_values(&self, query: &[f64]) -> Result<Vec<f64>, RecognizeError> {
        let q = self.scaled(query)?;
        let dim = self.dim;
        Ok(self
            .machines
            .iter()
            .map(|m| {
                m.support
                    .iter()
                    .map(|&(t, coef)| {
                        coef * self.params.kernel.eval(&self.points[t * dim..(t + 1) * dim], &q)
                    })
                    .sum::<f64>()
                    - m.rho
            })
            .collect())
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
        let dec = self.decision_values(query)?;
        let k = self.classes;
        let mut r = vec![vec![0.0; k]; k];
        for (m, d) in self.machines.iter().zip(&dec) {
            let (a, b) = m.sigmoid.ok_or(RecognizeError::NoProbability)?;
            let p = sigmoid_predict(*d, a, b).clamp(1e-7, 1.0 - 1e-7);
            r[m.classes.0][m.classes.1] = p;
            r[m.classes.1][m.classes.0] = 1.0 - p;
        }
        Ok(pairwise_coupling(&r))
    }
}

/// SMO on the C-SVC dual with Gram matrix `k` (row-major, n × n) and labels ±1 (`p = −1`), by
/// svm's core; `None` if it did not converge.
fn solve(k: &[f64], y: &[f64], settings: &SmoSettings) -> Option<SmoSolution> {
    let mut rows = GramRows::new(k, y.len())?;
    let linear = vec![-1.0; y.len()];
    svm::solve_smo(&mut rows, y, &linear, settings).ok()
}

/// Decision values of each of a pair's points from a machine trained without its fold.
fn cross_validated_decisions<'a>(
    members: &[usize],
    y: &[f64],
    params: &SvcParams,
    settings: &SmoSettings,
    row: &impl Fn(usize) -> &'a [f64],
    rng: &mut SplitMix64,
    tick: &dyn Fn(),
) -> Option<Vec<f64>> {
    let n = members.len();
    // A Fisher–Yates shuffle, then folds of consecutive positions (libsvm's layout).
    let mut order: Vec<usize> = (0..n).collect();
    for a in (1..n).rev() {
        order.swap(a, rng.below(a + 1));
    }
    let mut dec = vec![0.0; n];
    for fold in 0..PROBABILITY_FOLDS {
        let (begin, end) = (fold * n / PROBABILITY_FOLDS, (fold + 1) * n / PROBABILITY_FOLDS);
        let test = &order[begin..end];
        let train: Vec<usize> = order[..begin].iter().chain(&order[end..]).copied().collect();
        let (positive, negative) = (
            train.iter().filter(|&&t| y[t] > 0.0).count(),
            train.iter().filter(|&&t| y[t] < 0.0).count(),
        );
        // One class only in training: libsvm's fallback, a constant decision of that sign.
        if positive == 0 || negative == 0 {
            let v = if positive > 0 {
                1.0
            } else if negative > 0 {
                -1.0
            } else {
                0.0
            };
            test.iter().for_each(|&t| dec[t] = v);
            tick();
            continue;
        }
        let m = train.len();
        let mut k = vec![0.0; m * m];
        for a in 0..m {
            for b in a..m {
                let v = params.kernel.eval(row(members[train[a]]), row(members[train[b]]));
                k[a * m + b] = v;
                k[b * m + a] = v;
            }
        }
        let ty: Vec<f64> = train.iter().map(|&t| y[t]).collect();
        let SmoSolution { alpha, rho, .. } = solve(&k, &ty, settings)?;
        for &t in test {
            let x = row(members[t]);
            dec[t] = train
                .iter()
                .zip(alpha.iter().zip(&ty))
                .filter(|(_, (a, _))| **a > 0.0)
                .map(|(&s, (a, ys))| a * ys * params.kernel.eval(row(members[s]), x))
                .sum::<f64>()
                - rho;
        }
        tick();
    }
    Some(dec)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(serde::Deserialize)]
    struct Fixture {
        c: f64,
        gamma: f64,
        coef0: f64,
        classes: usize,
        x_train: Vec<Vec<f64>>,
        y_train: Vec<usize>,
        x_test: Vec<Vec<f64>>,
        decision_ovo: Vec<Vec<f64>>,
        predicted: Vec<usize>,
        n_support: Vec<usize>,
        coupling: Vec<Coupling>,
    }

    #[derive(serde::Deserialize)]
    struct Coupling {
        r: Vec<Vec<f64>>,
        p: Vec<f64>,
    }

    fn fixture() -> Fixture {
        serde_json::from_str(include_str!("../../fixtures/svc_poly2_4class.json")).expect("fixture")
    }

    #[test]
    fn decision_values_and_predictions_match_scikit_learn() {
        let f = fixture();
        let params = SvcParams {
            c: f.c,
            kernel: Kernel::Polynomial {
                gamma: f.gamma,
                coef0: f.coef0,
                degree: 2,
            },
            tolerance: 1e-10,
            scaling: FeatureScaling::None,
            probability: false,
            seed: 0,
            max_iterations: 0,
        };
        let svc = Svc::fit(params, &f.x_train, &f.y_train, f.classes).expect("fit");
        let mut worst: f64 = 0.0;
        for ((x, expected), label) in f.x_test.iter().zip(&f.decision_ovo).zip(&f.predicted) {
            let dec = svc.decision_values(x).expect("query");
            for (a, b) in dec.iter().zip(expected) {
                worst = worst.max((a - b).abs());
            }
            assert_eq!(svc.predict(x).expect("query"), *label, "{dec:?} vs {expected:?}");
        }
        // libsvm caches the kernel matrix in single precision (`Qfloat`), so its decision
        // values carry errors of ~1e-7 relative per kernel entry; ours are in double.
        assert!(worst < 1e-5, "largest decision difference {worst}");
        // Support vectors per class, counted as libsvm does (a point is one if any pair uses it).
        let mut is_sv = vec![false; f.x_train.len()];
        for m in svc.machines() {
            for &(t, _) in &m.support {
                is_sv[t] = true;
            }
        }
        let per_class: Vec<usize> = (0..f.classes)
            .map(|c| {
                (0..is_sv.len())
                    .filter(|&t| is_sv[t] && f.y_train[t] == c)
                    .count()
            })
            .collect();
        assert_eq!(per_class, f.n_support);
    }

    #[test]
    fn pairwise_coupling_finds_the_method_2_minimiser() {
        for case in fixture().coupling {
            let p = pairwise_coupling(&case.r);
            assert!((p.iter().sum::<f64>() - 1.0).abs() < 1e-12);
            for (a, b) in p.iter().zip(&case.p) {
                assert!((a - b).abs() < 1e-9, "{p:?} vs {:?}", case.p);
            }
        }
        // Consistent pairwise probabilities r_ij = p_i / (p_i + p_j) give p back exactly.
        let truth = [0.5, 0.3, 0.2];
        let r: Vec<Vec<f64>> = (0..3)
            .map(|i| {
                (0..3)
                    .map(|j| {
                        if i == j {
                            0.0
                        } else {
                            truth[i] / (truth[i] + truth[j])
                        }
                    })
                    .collect()
            })
            .collect();
        let p = pairwise_coupling(&r);
        for (a, b) in p.iter().zip(truth) {
            assert!((a - b).abs() < 1e-10, "{p:?}");
        }
    }

    #[test]
    fn probabilities_follow_the_classes_and_platt_fits_a_separable_sample() {
        let f = fixture();
        let svc = Svc::fit(
            SvcParams {
                c: f.c,
                kernel: Kernel::Polynomial {
                    gamma: f.gamma,
                    coef0: f.coef0,
                    degree: 2,
                },
                scaling: FeatureScaling::None,
                ..SvcParams::default()
            },
            &f.x_train,
            &f.y_train,
            f.classes,
        )
        .expect("fit");
        let mut agree = 0;
        for x in &f.x_test {
            let p = svc.predict_proba(x).expect("probabilities");
            assert!((p.iter().sum::<f64>() - 1.0).abs() < 1e-9 && p.iter().all(|v| (0.0..=1.0).contains(v)));
            let best = p
                .iter()
                .enumerate()
                .fold(0, |b, (i, v)| if *v > p[b] { i } else { b });
            agree += usize::from(best == svc.predict(x).expect("predict"));
        }
        assert!(agree * 10 >= f.x_test.len() * 8, "{agree} of {}", f.x_test.len());
        // Separable decisions: a sigmoid falling through 0 (A < 0, B ≈ 0 by symmetry), kept
        // from a step by the fit's regularised targets (3 + 1)/(3 + 2) and 1/(3 + 2).
        let dec = [-2.0, -1.5, -1.0, 1.0, 1.5, 2.0];
        let y = [-1.0, -1.0, -1.0, 1.0, 1.0, 1.0];
        let (a, b) = sigmoid_train(&dec, &y);
        assert!(a < -0.5 && b.abs() < 1e-6, "{a} {b}");
        assert!(sigmoid_predict(2.0, a, b) > 0.75 && sigmoid_predict(-2.0, a, b) < 0.25);
    }

    /// Three overlapping classes in the plane, `per_group` points of each in each of `groups`
    /// groups (trials), from a fixed seed.
    fn overlapping_blobs(groups: u64, per_group: usize) -> (Vec<[f64; 2]>, Vec<usize>, Vec<u64>) {
        let centres = [[0.0, 0.0], [1.0, 0.2], [0.4, 0.9]];
        let mut rng = SplitMix64::new(7);
        let (mut x, mut y, mut g) = (Vec::new(), Vec::new(), Vec::new());
        for group in 0..groups {
            for (class, centre) in centres.iter().enumerate() {
                for _ in 0..per_group {
                    let (a, b) = (rng.next_f64() - 0.5, rng.next_f64() - 0.5);
                    x.push([centre[0] + 1.2 * a, centre[1] + 1.2 * b]);
                    y.push(class);
                    g.push(group);
                }
            }
        }
        (x, y, g)
    }

    #[test]
    fn inner_cross_validation_picks_the_c_of_a_brute_force_search() {
        let (x, y, groups) = overlapping_blobs(4, 6);
        let params = SvcParams {
            kernel: Kernel::Polynomial {
                gamma: 1.0,
                coef0: 1.0,
                degree: 2,
            },
            scaling: FeatureScaling::None,
            ..SvcParams::default()
        };
        let grid = [1e-2, 1e-1, 1.0, 10.0, 100.0, 1e3];
        // Brute force: leave each group out in turn (4 groups, 4 folds), fit on the rest with
        // every class present, count the held-out points classified right.
        let brute: Vec<f64> = grid
            .iter()
            .map(|&c| {
                let mut right = 0;
                for held in 0..4 {
                    let train: Vec<usize> = (0..x.len()).filter(|&i| groups[i] != held).collect();
                    let tx: Vec<[f64; 2]> = train.iter().map(|&i| x[i]).collect();
                    let ty: Vec<usize> = train.iter().map(|&i| y[i]).collect();
                    let svc = Svc::fit(SvcParams { c, ..params }, &tx, &ty, 3).expect("fit");
                    right += (0..x.len())
                        .filter(|&i| groups[i] == held && svc.predict(&x[i]).expect("predict") == y[i])
                        .count();
                }
                right as f64 / x.len() as f64
            })
            .collect();
        let best = brute
            .iter()
            .enumerate()
            .fold(0, |b, (i, &a)| if a > brute[b] { i } else { b });
        // The grid (given unordered, with a repeat) is searched in ascending order.
        let unordered = [1e3, 1.0, 1e-2, 100.0, 1e-1, 10.0, 1.0];
        let search = select_c(params, &unordered, &x, &y, &groups, 3, 4).expect("search");
        eprintln!("brute force {brute:?}, search {search:?}");
        assert_eq!(search.folds, 4);
        assert_eq!(search.grid.iter().map(|p| p.c).collect::<Vec<_>>(), grid);
        for (p, a) in search.grid.iter().zip(&brute) {
            assert!((p.accuracy - a).abs() < 1e-15, "{search:?} vs {brute:?}");
        }
        assert_eq!(search.chosen_c, grid[best]);
        assert_eq!(search.accuracy(), Some(brute[best]));
        assert!(search.check().is_ok());
        // The problem discriminates: the candidates do not all score the same, and the choice
        // is an inner one (neither the smallest nor the largest C).
        assert!(brute.iter().any(|&a| a != brute[0]), "{brute:?}");
        assert!(best > 0 && best < grid.len() - 1, "{brute:?}");
        // Measured: C = 100 and 1000 tie at 65/72; the tie goes to the smaller C.
        assert_eq!(brute[4], brute[5], "{brute:?}");
        assert_eq!(search.chosen_c, 100.0);

        // One group cannot be cross-validated; a class seen in one group only is held out
        // once with no training vector of its own and counts as wrong.
        assert!(matches!(
            select_c(params, &grid, &x, &y, &[0; 72], 3, 4),
            Err(RecognizeError::TooFewGroups { groups: 1, folds: 4 })
        ));
        // Class 2 of group 0 relabelled as a class 3 found nowhere else.
        let lonely: Vec<usize> = (0..x.len())
            .map(|i| if groups[i] == 0 && y[i] == 2 { 3 } else { y[i] })
            .collect();
        let a = cross_validated_accuracy(SvcParams { c: 1.0, ..params }, &x, &lonely, &groups, 4, 4)
            .expect("folds without class 3 still fit");
        assert!(a < brute[2], "{a} vs {}", brute[2]);
    }

    #[test]
    fn a_candidate_that_does_not_converge_is_skipped_with_a_warning() {
        let (x, y, groups) = overlapping_blobs(4, 6);
        // On these overlapping classes 200 SMO iterations finish C = 10⁻² and 1 (about 50
        // needed) but not C ≥ 100 (over 500 needed): the large C stands for one whose fit
        // would run out the solver's budget.
        let params = SvcParams {
            kernel: Kernel::Polynomial {
                gamma: 1.0,
                coef0: 1.0,
                degree: 2,
            },
            scaling: FeatureScaling::None,
            max_iterations: 200,
            ..SvcParams::default()
        };
        let events = std::sync::Mutex::new(Vec::new());
        let record = |e: FitEvent| events.lock().expect("events").push(e);
        let search = select_c_observed(params, &[1e4, 1e-2, 1.0], &x, &y, &groups, 3, 4, &record)
            .expect("the converging candidates are searched");
        assert_eq!(search.grid.iter().map(|p| p.c).collect::<Vec<_>>(), [1e-2, 1.0]);
        assert_eq!(search.chosen_c, 1.0, "{search:?}");
        let events = events.into_inner().expect("events");
        let skipped: Vec<String> = events
            .iter()
            .filter_map(|e| match e {
                FitEvent::SkippedC { c, error } => Some(format!("{c:e}: {error}")),
                _ => None,
            })
            .collect();
        assert_eq!(skipped.len(), 1, "{events:?}");
        assert!(
            skipped[0].starts_with("1e4: SMO did not converge in 200 iterations at C = 1e4 (classes "),
            "{skipped:?}"
        );
        // One step whose units are the machines of every candidate and fold (3 pairs × 4
        // folds × 3 candidates); the skipped candidate stops at its first failure.
        assert!(
            matches!(events[0], FitEvent::Step { total: 36, .. }),
            "{events:?}"
        );
        let advanced = events.iter().filter(|e| matches!(e, FitEvent::Advance)).count();
        assert!((24..36).contains(&advanced), "{advanced}");

        // Every candidate failing is an error that lists each.
        match select_c(params, &[1e2, 1e4], &x, &y, &groups, 3, 4) {
            Err(e @ RecognizeError::EveryCFailed { .. }) => {
                let text = e.to_string();
                assert!(
                    text.starts_with("every candidate C failed: C = 1e2: SMO did not converge")
                        && text.contains("; C = 1e4: SMO did not converge in 200 iterations at C = 1e4"),
                    "{text}"
                );
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn a_fold_without_a_class_names_the_callers_classes() {
        let (x, y, _) = overlapping_blobs(2, 6);
        // Fold 0 holds every vector of class 0, so the fold's fit sees classes 1 and 2 as its
        // own 0 and 1; 5 iterations are too few for any pair.
        let fold: Vec<usize> = y.iter().map(|&l| usize::from(l != 0)).collect();
        let params = SvcParams {
            scaling: FeatureScaling::None,
            probability: false,
            max_iterations: 5,
            ..SvcParams::default()
        };
        assert!(matches!(
            c_search::fold_correct(params, &x, &y, &fold, 0, 3, &|| {}),
            Err(RecognizeError::NotConverged {
                iterations: 5,
                first: 1,
                second: 2,
                ..
            })
        ));
    }

    #[test]
    fn bad_input_is_an_error() {
        let x = [vec![0.0, 1.0], vec![1.0, 0.0]];
        let fit = |p: SvcParams, labels: &[usize], classes| Svc::fit(p, &x, labels, classes).err();
        assert!(matches!(
            fit(
                SvcParams {
                    c: 0.0,
                    ..SvcParams::default()
                },
                &[0, 1],
                2
            ),
            Some(RecognizeError::Parameter {
                of: "SVC parameter",
                name: "c",
                ..
            })
        ));
        assert!(matches!(
            fit(SvcParams::default(), &[0, 2], 2),
            Some(RecognizeError::LabelOutOfRange {
                index: 1,
                label: 2,
                classes: 2
            })
        ));
        assert!(matches!(
            fit(SvcParams::default(), &[0, 0], 2),
            Some(RecognizeError::EmptyClass { class: 1 })
        ));
        assert!(matches!(
            fit(SvcParams::default(), &[0], 2),
            Some(RecognizeError::Counts { .. })
        ));
        let svc = Svc::fit(
            SvcParams {
                probability: false,
                ..SvcParams::default()
            },
            &x,
            &[0, 1],
            2,
        )
        .expect("fit");
        assert!(matches!(
            svc.predict_proba(&[0.0, 1.0]),
            Err(RecognizeError::NoProbability)
        ));
        assert!(matches!(
            svc.predict(&[0.0]),
            Err(RecognizeError::Dimension { got: 1, .. })
        ));
        assert!(matches!(
            svc.predict(&[f64::NAN, 0.0]),
            Err(RecognizeError::NonFinite { index: 0 })
        ));
        assert_eq!(svc.predict(&[0.0, 1.0]).ok(), Some(0));
    }
}

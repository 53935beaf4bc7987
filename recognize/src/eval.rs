//! Evaluating a recognizer: a confusion matrix over any label type, per-class rates and
//! accuracy, and a text table in percent of each true class (as Nakano's Fig. 4.15 and Sinapov's
//! confusion figures print them).
//!
//! Counts are integers so that matrices from several runs (SOM seeds, cross-validation folds)
//! can be [merged](ConfusionMatrix::merge): pooled counts over runs of equal size give the
//! average of the runs' rates, as Fig. 4.15 averages 10 SOM seeds.

use std::cmp::Ordering;
use std::fmt::{Display, Write as _};

use crate::RecognizeError;
use crate::UsageError;

/// Counts of (true class, predicted class) over a fixed, ordered set of classes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ConfusionMatrix<L> {
    classes: Vec<L>,
    /// `counts[t][p]`: samples of true class `t` predicted as `p`.
    counts: Vec<Vec<u64>>,
}

impl<L: PartialEq + std::fmt::Debug> ConfusionMatrix<L> {
    /// An empty matrix over `classes` (rows and columns in this order).
    pub fn new(classes: Vec<L>) -> Result<Self, RecognizeError> {
        for (i, c) in classes.iter().enumerate() {
            if classes[..i].contains(c) {
                return Err(RecognizeError::Usage(UsageError::DuplicateClass(format!(
                    "{c:?}"
                ))));
            }
        }
        let n = classes.len();
        Ok(Self {
            classes,
            counts: vec![vec![0; n]; n],
        })
    }

    fn index(&self, label: &L) -> Result<usize, RecognizeError> {
        self.classes
            .iter()
            .position(|c| c == label)
            .ok_or_else(|| RecognizeError::Usage(UsageError::UnknownLabel(format!("{label:?}"))))
    }

    /// Records one sample of class `truth` predicted as `predicted`.
    pub fn add(&mut self, truth: &L, predicted: &L) -> Result<(), RecognizeError> {
        let (t, p) = (self.index(truth)?, self.index(predicted)?);
        self.counts[t][p] += 1;
        Ok(())
    }

    /// Adds another matrix's counts (same classes, same order).
    pub fn merge(&mut self, other: &Self) -> Result<(), RecognizeError> {
        if self.classes != other.classes {
            return Err(RecognizeError::Usage(UsageError::MatrixClasses));
        }
        for (row, other_row) in self.counts.iter_mut().zip(&other.counts) {
            for (c, o) in row.iter_mut().zip(other_row) {
                *c += o;
            }
        }
        Ok(())
    }

    /// The classes, in row order.
    pub fn classes(&self) -> &[L] {
        &self.classes
    }

    /// `counts()[t][p]`: samples of true class `t` predicted as `p`.
    pub fn counts(&self) -> &[Vec<u64>] {
        &self.counts
    }

    /// Samples recorded.
    pub fn total(&self) -> u64 {
        self.counts.iter().flatten().sum()
    }

    /// Fraction predicted correctly; `None` before any sample.
    pub fn accuracy(&self) -> Option<f64> {
        let total = self.total();
        let correct: u64 = (0..self.classes.len()).map(|i| self.counts[i][i]).sum();
        (total > 0).then(|| correct as f64 / total as f64)
    }

    /// Per class, the fraction of its samples recognized as it (recall); `None` for a class with
    /// no samples.
    pub fn per_class_rates(&self) -> Vec<Option<f64>> {
        self.counts
            .iter()
            .enumerate()
            .map(|(i, row)| {
                let n: u64 = row.iter().sum();
                (n > 0).then(|| row[i] as f64 / n as f64)
            })
            .collect()
    }

    /// Each row in percent of its true class's samples (0 for an empty row).
    pub fn row_percent(&self) -> Vec<Vec<f64>> {
        self.counts
            .iter()
            .map(|row| {
                let n: u64 = row.iter().sum();
                row.iter()
                    .map(|&c| if n > 0 { 100.0 * c as f64 / n as f64 } else { 0.0 })
                    .collect()
            })
            .collect()
    }
}

impl<L: PartialEq + std::fmt::Debug + Display> ConfusionMatrix<L> {
    /// The row (and column) indices in natural order of the classes' names
    /// ([`natural_cmp`]): `mat2` before `mat10`, as a reader counts them.
    pub fn natural_order(&self) -> Vec<usize> {
        let names: Vec<String> = self.classes.iter().map(ToString::to_string).collect();
        let mut order: Vec<usize> = (0..names.len()).collect();
        order.sort_by(|&a, &b| natural_cmp(&names[a], &names[b]));
        order
    }

    /// The matrix as text: one row per true class in natural order of the names
    /// ([`ConfusionMatrix::natural_order`]), columns numbered as the rows, values in percent of
    /// the row, the class's rate at the end, and the accuracy over every decision counted.
    pub fn to_text(&self) -> String {
        let order = self.natural_order();
        let width = self
            .classes
            .iter()
            .map(|c| c.to_string().len())
            .max()
            .unwrap_or(0)
            .max(5);
        let mut header = format!("{:width$}   ", "true \\ pred", width = width + 4);
        for j in 0..self.classes.len() {
            let _ = write!(header, "{:>6}", j + 1);
        }
        header.push_str("    rate\n");
        let mut text = header;
        let percent = self.row_percent();
        for (shown, &i) in order.iter().enumerate() {
            let _ = write!(
                text,
                "{:>2}  {:<width$}   ",
                shown + 1,
                self.classes[i].to_string()
            );
            for &j in &order {
                let _ = write!(text, "{:>6.1}", percent[i][j]);
            }
            let _ = writeln!(text, "  {:>5.1} %", percent[i][i]);
        }
        if let Some(a) = self.accuracy() {
            let _ = writeln!(
                text,
                "accuracy {:.1} % over {} decisions",
                100.0 * a,
                self.total()
            );
        }
        text
    }
}

/// The decision that names a stroke's surface for good: the first of the trailing decisions
/// `right` accepts, as an index into `decisions`; `None` when the last decision is wrong or
/// there is none. Offline evaluation, anytime evaluation and a session's live timing all read
/// "stable right" this one way.
pub fn stable_right_from<T>(decisions: &[T], right: impl Fn(&T) -> bool) -> Option<usize> {
    if !decisions.last().is_some_and(&right) {
        return None;
    }
    Some(
        decisions
            .iter()
            .rposition(|d| !right(d))
            .map_or(0, |wrong| wrong + 1),
    )
}

/// A decision that named a surface, as [`DecisionTiming::of`] reads it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NamedDecision {
    /// When, s after the stroke's start.
    pub time_s: f64,
    /// The tool's path by then since the stroke's start, m; `None` where it is not known.
    pub travel_m: Option<f64>,
    /// Whether it named the surface under the tool.
    pub right: bool,
}

/// How soon one stroke's surface was named: the one "stable right" type that offline
/// evaluation (each capture of an anytime evaluation) and a live session (each rubbed
/// segment of the report) both compute, through [`stable_right_from`].
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct DecisionTiming {
    /// The first named decision, s after the stroke's start.
    pub first_named_after_s: Option<f64>,
    /// The named decision that starts the final run of right ones, s after the stroke's
    /// start; `None` when the stroke does not end named right.
    pub stable_right_after_s: Option<f64>,
    /// The same decision in travel, how much of the surface it took, m.
    pub stable_right_after_m: Option<f64>,
    /// Decisions that named a surface.
    pub named: usize,
    /// Of those, named right.
    pub right: usize,
}

impl DecisionTiming {
    /// The timing of a stroke whose named decisions, in time order, are `named`.
    pub fn of(named: &[NamedDecision]) -> Self {
        let stable = stable_right_from(named, |d| d.right).map(|k| named[k]);
        Self {
            first_named_after_s: named.first().map(|d| d.time_s),
            stable_right_after_s: stable.map(|d| d.time_s),
            stable_right_after_m: stable.and_then(|d| d.travel_m),
            named: named.len(),
            right: named.iter().filter(|d| d.right).count(),
        }
    }
}

/// Natural order of names: runs of ASCII digits compare as numbers (`mat2` < `mat10`, and
/// `mat02` = `mat2` numerically, the shorter spelling first), everything else as text; names
/// equal that way fall back to plain string order, so the order is total.
pub fn natural_cmp(a: &str, b: &str) -> Ordering {
    let (mut x, mut y) = (a, b);
    while let (Some(cx), Some(cy)) = (x.chars().next(), y.chars().next()) {
        let order = if cx.is_ascii_digit() && cy.is_ascii_digit() {
            let (nx, rest_x) = split_digits(x);
            let (ny, rest_y) = split_digits(y);
            (x, y) = (rest_x, rest_y);
            let (tx, ty) = (nx.trim_start_matches('0'), ny.trim_start_matches('0'));
            // Without leading zeros, a longer run is a larger number; equal lengths compare
            // digit by digit, so runs of any length never overflow.
            tx.len()
                .cmp(&ty.len())
                .then_with(|| tx.cmp(ty))
                .then_with(|| nx.len().cmp(&ny.len()))
        } else {
            (x, y) = (&x[cx.len_utf8()..], &y[cy.len_utf8()..]);
            cx.cmp(&cy)
        };
        if order != Ordering::Equal {
            return order;
        }
    }
    x.len().cmp(&y.len()).then_with(|| a.cmp(b))
}

/// The leading ASCII digits of `s`, and the rest.
fn split_digits(s: &str) -> (&str, &str) {
    let end = s.find(|c: char| !c.is_ascii_digit()).unwrap_or(s.len());
    s.split_at(end)
}

#[cfg(test)]
mod tests {

    #[test]
    fn stable_right_starts_the_final_run_of_right_decisions() {
        let right = |d: &char| *d == 'a';
        assert_eq!(stable_right_from(&['b', 'a', 'b', 'a', 'a'], right), Some(3));
        assert_eq!(stable_right_from(&['a', 'a'], right), Some(0));
        assert_eq!(stable_right_from(&['a', 'b'], right), None);
        assert_eq!(stable_right_from::<char>(&[], right), None);
    }
    use super::*;

    #[test]
    fn counts_rates_merging_and_text() {
        let mut m = ConfusionMatrix::new(vec!["a", "b", "c"]).expect("distinct");
        for (t, p) in [("a", "a"), ("a", "b"), ("b", "b"), ("b", "b"), ("c", "a")] {
            m.add(&t, &p).expect("known");
        }
        assert_eq!(m.total(), 5);
        assert_eq!(m.accuracy(), Some(0.6));
        assert_eq!(m.per_class_rates(), vec![Some(0.5), Some(1.0), Some(0.0)]);
        let mut pooled = m.clone();
        pooled.merge(&m).expect("same classes");
        assert_eq!(pooled.counts()[0], vec![2, 2, 0]);
        assert_eq!(pooled.accuracy(), Some(0.6));
        let text = m.to_text();
        assert!(text.contains(" 1  a"), "{text}");
        assert!(text.contains("50.0"), "{text}");
        assert!(text.contains("accuracy 60.0 %"), "{text}");
        assert!(text.contains("over 5 decisions"), "{text}");
    }

    #[test]
    fn names_sort_naturally() {
        let mut names = vec![
            "mat10", "mat2", "mat1", "mat11", "b", "a9b", "a10", "mat02", "mat",
        ];
        names.sort_by(|a, b| natural_cmp(a, b));
        assert_eq!(
            names,
            [
                "a9b", "a10", "b", "mat", "mat1", "mat2", "mat02", "mat10", "mat11"
            ]
        );
        assert_eq!(
            natural_cmp("x99999999999999999999999", "x100000000000000000000000"),
            Ordering::Less
        );
        assert_eq!(natural_cmp("same", "same"), Ordering::Equal);
    }

    #[test]
    fn text_shows_classes_in_natural_order() {
        let classes: Vec<String> = ["mat1", "mat10", "mat11", "mat2"].map(String::from).to_vec();
        let mut m = ConfusionMatrix::new(classes).expect("distinct");
        // mat2 is taken for mat10 once in two; every other class is always right.
        for (t, p) in [
            ("mat1", "mat1"),
            ("mat10", "mat10"),
            ("mat11", "mat11"),
            ("mat2", "mat2"),
            ("mat2", "mat10"),
        ] {
            m.add(&t.to_owned(), &p.to_owned()).expect("known");
        }
        assert_eq!(m.natural_order(), vec![0, 3, 1, 2]);
        let text = m.to_text();
        let rows: Vec<&str> = text.lines().skip(1).take(4).collect();
        let names: Vec<&str> = rows
            .iter()
            .map(|r| r.split_whitespace().nth(1).expect("name"))
            .collect();
        assert_eq!(names, ["mat1", "mat2", "mat10", "mat11"], "{text}");
        // Columns follow the rows: mat2's row is 0, 50, 50, 0 in that order.
        let cells: Vec<&str> = rows[1].split_whitespace().skip(2).take(4).collect();
        assert_eq!(cells, ["0.0", "50.0", "50.0", "0.0"], "{text}");
        assert!(rows[1].ends_with("50.0 %"), "{text}");
        assert!(text.contains("accuracy 80.0 % over 5 decisions"), "{text}");
        // The matrix itself keeps its classes' order.
        assert_eq!(m.classes()[1], "mat10");
    }

    #[test]
    fn bad_labels_are_errors() {
        let mut m = ConfusionMatrix::new(vec![1, 2]).expect("distinct");
        assert!(matches!(m.add(&1, &3), Err(RecognizeError::Usage(UsageError::UnknownLabel(l))) if l == "3"));
        assert_eq!(m.accuracy(), None);
        assert_eq!(m.per_class_rates(), vec![None, None]);
        assert!(ConfusionMatrix::new(vec![1, 1]).is_err());
        let other = ConfusionMatrix::new(vec![2, 1]).expect("distinct");
        assert!(matches!(
            m.merge(&other),
            Err(RecognizeError::Usage(UsageError::MatrixClasses))
        ));
    }
}

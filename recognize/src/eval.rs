//! Evaluating a recognizer: a confusion matrix over any label type, per-class rates and
//! accuracy, and a text table in percent of each true class (as Nakano's Fig. 4.15 and Sinapov's
//! confusion figures print them).
//!
//! Counts are integers so that matrices from several runs (SOM seeds, cross-validation folds)
//! can be [merged](ConfusionMatrix::merge): pooled counts over runs of equal size give the
//! average of the runs' rates, as Fig. 4.15 averages 10 SOM seeds.

use std::fmt::{Display, Write as _};

use crate::RecognizeError;

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
                return Err(RecognizeError::DuplicateClass(format!("{c:?}")));
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
            .ok_or_else(|| RecognizeError::UnknownLabel(format!("{label:?}")))
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
            return Err(RecognizeError::MatrixClasses);
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
    /// The matrix as text: one row per true class, columns numbered as the rows, values in
    /// percent of the row, and the class's rate at the end.
    pub fn to_text(&self) -> String {
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
        for (i, (class, row)) in self.classes.iter().zip(self.row_percent()).enumerate() {
            let _ = write!(text, "{:>2}  {:<width$}   ", i + 1, class.to_string());
            for v in &row {
                let _ = write!(text, "{v:>6.1}");
            }
            let _ = writeln!(text, "  {:>5.1} %", row[i]);
        }
        if let Some(a) = self.accuracy() {
            let _ = writeln!(text, "accuracy {:.1} % over {} samples", 100.0 * a, self.total());
        }
        text
    }
}

#[cfg(test)]
mod tests {
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
    }

    #[test]
    fn bad_labels_are_errors() {
        let mut m = ConfusionMatrix::new(vec![1, 2]).expect("distinct");
        assert!(matches!(m.add(&1, &3), Err(RecognizeError::UnknownLabel(l)) if l == "3"));
        assert_eq!(m.accuracy(), None);
        assert_eq!(m.per_class_rates(), vec![None, None]);
        assert!(ConfusionMatrix::new(vec![1, 1]).is_err());
        let other = ConfusionMatrix::new(vec![2, 1]).expect("distinct");
        assert!(matches!(m.merge(&other), Err(RecognizeError::MatrixClasses)));
    }
}

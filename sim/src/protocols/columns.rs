//! A capture under construction: named columns filled row by row.

use capture::{Capture, CaptureError, Metadata};

pub(crate) struct Columns {
    names: Vec<String>,
    data: Vec<Vec<f64>>,
}

impl Columns {
    pub(crate) fn new(names: &[&str]) -> Self {
        Self {
            names: names.iter().map(|&n| n.to_owned()).collect(),
            data: vec![Vec::new(); names.len()],
        }
    }

    /// Appends one row; the protocol code fixes the row width, so a mismatch is a bug caught by
    /// `Capture::new`'s validation rather than here.
    pub(crate) fn push(&mut self, row: &[f64]) {
        for (column, &value) in self.data.iter_mut().zip(row) {
            column.push(value);
        }
    }

    pub(crate) fn into_capture(self, meta: Metadata) -> Result<Capture, CaptureError> {
        Capture::new(meta, self.names, self.data)
    }
}

//! What the commands print: the tables and JSON objects of their results, apart from the
//! commands so that each command reads as parse → call → print.

// These tables are where palpus talks to its user.
#![allow(clippy::print_stdout)]

pub(crate) mod anytime;
pub(crate) mod identification;
pub(crate) mod recognition;
pub(crate) mod recognition_cv;

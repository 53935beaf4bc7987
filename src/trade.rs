//! The speed/accuracy trade of a model's fit: the table `palpus bench trade` writes
//! (`trade.csv`), read back, and the point a scene's budget picks from it.
//!
//! The table's first line says what was measured: the model kind and the SHA-256 of the
//! training capture's bytes, so that a scene never picks hyperparameters from a front measured
//! on another capture (its own capture changed, or the wrong file was named).

use std::path::{Path, PathBuf};

use identify::{ModelKind, SearchPoint};

/// The start of a trade table's first line.
const MAGIC: &str = "# palpus-trade format=1";

/// The table's columns, in order.
pub const COLUMNS: [&str; 17] = [
    "n",
    "c",
    "epsilon",
    "gamma",
    "tol",
    "max_sv",
    "cv_aise",
    "n_sv",
    "fit_s",
    "predict_ns",
    "test_aise",
    "test_max_error",
    "test_peak_error",
    "test_predict_ns",
    "test_predict_f32_ns",
    "on_front",
    "failed",
];

/// What a point measured on the held-out capture.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeldOut {
    /// AISE, N².
    pub aise: f64,
    /// Largest error, N.
    pub max_error_n: f64,
    /// Error in the peak force, N.
    pub peak_error_n: f64,
    /// Time of one prediction of the model refitted on the whole capture, ns (the exact f64
    /// evaluation).
    pub predict_ns: f64,
    /// The same through the haptic loop's f32 fast path, ns.
    pub predict_f32_ns: f64,
}

/// One measured point: a grid point cross-validated at a training size, and what it gave on
/// the held-out capture.
#[derive(Debug, Clone, PartialEq)]
pub struct TradeRow {
    /// Training size (the needle's in-tissue samples; the other models use every row).
    pub n: usize,
    /// Solver tolerance of every fit (`None`: the library's default).
    pub tol: Option<f64>,
    /// Support-vector budget of every fit (`None`: none).
    pub max_sv: Option<usize>,
    /// The hyperparameters and their cross-validation, as `identify --search` measures them.
    pub point: SearchPoint,
    /// Measures on the held-out capture, when one was given.
    pub held_out: Option<HeldOut>,
    /// On the Pareto front over [`TradeRow::time_ns`] and [`TradeRow::aise`].
    pub on_front: bool,
}

impl TradeRow {
    /// The accuracy the front is drawn over: held-out AISE when measured, else cross-validated.
    pub fn aise(&self) -> f64 {
        self.held_out.map_or(self.point.cv_aise, |h| h.aise)
    }

    /// The time per prediction the front is drawn over: the refitted model's over the test
    /// capture when measured, else the cross-validation folds' mean.
    pub fn time_ns(&self) -> f64 {
        self.held_out.map_or(self.point.predict_ns, |h| h.predict_ns)
    }

    /// Measured, with a finite time and accuracy.
    pub fn ok(&self) -> bool {
        self.point.failed.is_none() && self.aise().is_finite() && self.time_ns().is_finite()
    }
}

/// Marks the rows no other beats on both time per prediction and AISE (failed rows never).
pub fn pareto_front(rows: &[TradeRow]) -> Vec<bool> {
    rows.iter()
        .map(|p| {
            p.ok()
                && !rows.iter().any(|q| {
                    q.ok()
                        && q.time_ns() <= p.time_ns()
                        && q.aise() <= p.aise()
                        && (q.time_ns() < p.time_ns() || q.aise() < p.aise())
                })
        })
        .collect()
}

/// A trade table: what was measured, and the points.
#[derive(Debug, Clone, PartialEq)]
pub struct TradeTable {
    /// The model kind.
    pub model: ModelKind,
    /// SHA-256 of the training capture's bytes ([`capture::sha256_hex`]).
    pub capture_sha256: String,
    /// The points, in the order measured.
    pub rows: Vec<TradeRow>,
}

/// A trade table that cannot be read: the file, the line (1-based), the column when one is to
/// blame, and why.
#[derive(Debug, thiserror::Error)]
#[error("{}: line {line}{}: {reason}", path.display(), column.map(|c| format!(", column `{c}`")).unwrap_or_default())]
pub struct TradeError {
    /// The file.
    pub path: PathBuf,
    /// The line, 1-based.
    pub line: usize,
    /// The column.
    pub column: Option<&'static str>,
    /// Why.
    pub reason: String,
}

impl TradeError {
    /// The error without the file: the line, the column and why.
    pub fn reason_with_place(&self) -> String {
        let column = self.column.map(|c| format!(", column `{c}`")).unwrap_or_default();
        format!("line {}{column}: {}", self.line, self.reason)
    }
}

/// What a scene asks of a model: at most this long per prediction, at most this AISE.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Budget {
    /// Longest time per prediction, ns.
    pub max_predict_ns: Option<f64>,
    /// Largest AISE, N².
    pub max_aise: Option<f64>,
}

impl Budget {
    fn admits(&self, row: &TradeRow) -> bool {
        row.ok()
            && self.max_predict_ns.is_none_or(|t| row.time_ns() <= t)
            && self.max_aise.is_none_or(|a| row.aise() <= a)
    }
}

impl std::fmt::Display for Budget {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut parts = Vec::new();
        if let Some(t) = self.max_predict_ns {
            parts.push(format!("max_predict_ns = {t}"));
        }
        if let Some(a) = self.max_aise {
            parts.push(format!("max_aise = {a:e} N²"));
        }
        f.write_str(&parts.join(" and "))
    }
}

/// The point a budget picked, and how many it chose from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Choice<'a> {
    /// The point.
    pub row: &'a TradeRow,
    /// Points within the budget.
    pub within: usize,
    /// Points measured (failed ones included).
    pub measured: usize,
}

impl TradeTable {
    /// Writes the table to `path` atomically (a good file is never replaced by a half-written
    /// one): the first line names the model and the capture's SHA-256.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        use std::io::Write as _;
        capture::write_atomically(path, |w| {
            writeln!(
                w,
                "{MAGIC} model={} capture_sha256={}",
                self.model.short_name(),
                self.capture_sha256
            )?;
            writeln!(w, "{}", COLUMNS.join(","))?;
            let num = |v: f64| {
                if v.is_finite() {
                    format!("{v:e}")
                } else {
                    String::new()
                }
            };
            for r in &self.rows {
                let h = |f: fn(&HeldOut) -> f64| r.held_out.as_ref().map_or(String::new(), |h| num(f(h)));
                let p = &r.point;
                let failed = p.failed.as_deref().unwrap_or("").replace(['"', '\n'], " ");
                writeln!(
                    w,
                    "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},\"{failed}\"",
                    r.n,
                    num(p.c),
                    num(p.epsilon),
                    p.gamma.map_or(String::new(), num),
                    r.tol.map_or(String::new(), num),
                    r.max_sv.map_or(String::new(), |k| k.to_string()),
                    num(p.cv_aise),
                    num(p.n_sv),
                    num(p.fit_seconds),
                    num(p.predict_ns),
                    h(|h| h.aise),
                    h(|h| h.max_error_n),
                    h(|h| h.peak_error_n),
                    h(|h| h.predict_ns),
                    h(|h| h.predict_f32_ns),
                    r.on_front,
                )?;
            }
            Ok(())
        })
    }

    /// Reads a table from `bytes` (the contents of `path`, named in errors).
    pub fn parse(bytes: &[u8], path: &Path) -> Result<Self, TradeError> {
        let error = |line: usize, column: Option<&'static str>, reason: String| TradeError {
            path: path.to_owned(),
            line,
            column,
            reason,
        };
        let text = std::str::from_utf8(bytes).map_err(|e| error(1, None, format!("not UTF-8: {e}")))?;
        let (first, rest) = text.split_once('\n').unwrap_or((text, ""));
        let Some(fields) = first.trim_end_matches('\r').strip_prefix(MAGIC) else {
            return Err(error(
                1,
                None,
                format!(
                    "not a trade table: the first line should start with `{MAGIC}` (written by `palpus bench trade`)"
                ),
            ));
        };
        let mut model = None;
        let mut capture_sha256 = None;
        for kv in fields.split_whitespace() {
            match kv.split_once('=') {
                Some(("model", v)) => {
                    model = Some(match v {
                        "hard" => ModelKind::HardFriction,
                        "soft" => ModelKind::SoftFriction,
                        "needle" => ModelKind::NeedlePuncture,
                        other => {
                            return Err(error(
                                1,
                                None,
                                format!("model `{other}`: expected hard, soft or needle"),
                            ));
                        }
                    });
                }
                Some(("capture_sha256", v)) => capture_sha256 = Some(v.to_owned()),
                _ => {}
            }
        }
        let model = model.ok_or_else(|| error(1, None, "no `model=` on the first line".into()))?;
        let capture_sha256 =
            capture_sha256.ok_or_else(|| error(1, None, "no `capture_sha256=` on the first line".into()))?;
        let mut reader = csv::ReaderBuilder::new()
            .has_headers(true)
            .from_reader(rest.as_bytes());
        let header = reader
            .headers()
            .map_err(|e| error(2, None, e.to_string()))?
            .clone();
        if header.iter().ne(COLUMNS) {
            return Err(error(
                2,
                None,
                format!("expected the columns {}", COLUMNS.join(",")),
            ));
        }
        let mut rows = Vec::new();
        for (i, record) in reader.records().enumerate() {
            let line = i + 3;
            let record = record.map_err(|e| error(line, None, e.to_string()))?;
            let cell = |j: usize| record.get(j).unwrap_or("");
            let number = |j: usize| -> Result<Option<f64>, TradeError> {
                let text = cell(j).trim();
                if text.is_empty() {
                    return Ok(None);
                }
                text.parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .map(Some)
                    .ok_or_else(|| error(line, Some(COLUMNS[j]), format!("`{text}` is not a finite number")))
            };
            let required = |j: usize| -> Result<f64, TradeError> {
                number(j)?.ok_or_else(|| error(line, Some(COLUMNS[j]), "empty".into()))
            };
            let n = cell(0)
                .trim()
                .parse::<usize>()
                .map_err(|_| error(line, Some("n"), format!("`{}` is not a sample count", cell(0))))?;
            let failed = Some(cell(16).trim()).filter(|f| !f.is_empty()).map(str::to_owned);
            // A failed point has no measures: every number but its hyperparameters may be empty.
            let measure = |j: usize| -> Result<f64, TradeError> {
                if failed.is_some() {
                    Ok(number(j)?.unwrap_or(f64::NAN))
                } else {
                    required(j)
                }
            };
            let held_out = match [10, 11, 12, 13, 14].map(number) {
                [
                    Ok(Some(aise)),
                    Ok(Some(max_error_n)),
                    Ok(Some(peak_error_n)),
                    Ok(Some(predict_ns)),
                    Ok(Some(predict_f32_ns)),
                ] => Some(HeldOut {
                    aise,
                    max_error_n,
                    peak_error_n,
                    predict_ns,
                    predict_f32_ns,
                }),
                [Ok(None), Ok(None), Ok(None), Ok(None), Ok(None)] => None,
                cells => {
                    if let Some(Err(e)) = cells.into_iter().find(Result::is_err) {
                        return Err(e);
                    }
                    return Err(error(
                        line,
                        None,
                        "the five test_ columns are either all given or all empty".into(),
                    ));
                }
            };
            let tol = number(4)?;
            let max_sv = match cell(5).trim() {
                "" => None,
                text => Some(text.parse::<usize>().ok().filter(|k| *k >= 1).ok_or_else(|| {
                    error(
                        line,
                        Some("max_sv"),
                        format!("`{text}` is not a support-vector count"),
                    )
                })?),
            };
            let on_front = match cell(15).trim() {
                "true" => true,
                "false" => false,
                other => {
                    return Err(error(
                        line,
                        Some("on_front"),
                        format!("`{other}`: expected true or false"),
                    ));
                }
            };
            let (c, epsilon, gamma) = (required(1)?, required(2)?, number(3)?);
            // A row is a model to fit: held to the rule every hyperparameter is held to.
            identify::Plausibility::check_hyperparameters(Some(c), Some(epsilon), gamma)
                .map_err(|(name, v, reason)| error(line, Some(name), format!("{v:e}: {reason}")))?;
            if let Some(t) = tol
                && !(t > 0.0 && t < 1.0)
            {
                return Err(error(
                    line,
                    Some("tol"),
                    format!("{t}: a relative tolerance in (0, 1)"),
                ));
            }
            let point = SearchPoint {
                c,
                epsilon,
                gamma,
                cv_aise: measure(6)?,
                n_sv: measure(7)?,
                fit_seconds: measure(8)?,
                predict_ns: measure(9)?,
                failed,
            };
            rows.push(TradeRow {
                n,
                tol,
                max_sv,
                point,
                held_out,
                on_front,
            });
        }
        if rows.is_empty() {
            return Err(error(3, None, "no points".into()));
        }
        Ok(Self {
            model,
            capture_sha256,
            rows,
        })
    }

    /// The cheapest point within `budget`: the least time per prediction among the points
    /// that meet every limit, ties to the lower AISE, then the smaller training size. Such a
    /// point is always on the front (a point that beats it on both would meet the budget too).
    /// `Err` says why none does: the fastest point and the most accurate, with what each gives.
    pub fn choose(&self, budget: &Budget) -> Result<Choice<'_>, String> {
        let within: Vec<&TradeRow> = self.rows.iter().filter(|r| budget.admits(r)).collect();
        if let Some(row) = within.iter().copied().min_by(|a, b| {
            a.time_ns()
                .total_cmp(&b.time_ns())
                .then(a.aise().total_cmp(&b.aise()))
                .then(a.n.cmp(&b.n))
        }) {
            return Ok(Choice {
                row,
                within: within.len(),
                measured: self.rows.len(),
            });
        }
        let ok: Vec<&TradeRow> = self.rows.iter().filter(|r| r.ok()).collect();
        let fastest = ok.iter().min_by(|a, b| a.time_ns().total_cmp(&b.time_ns()));
        let best = ok.iter().min_by(|a, b| a.aise().total_cmp(&b.aise()));
        Err(match (fastest, best) {
            (Some(f), Some(b)) => format!(
                "none of the {} measured points meets {budget}: the fastest takes {:.0} ns at an AISE of {:.3e} N², the most accurate reaches {:.3e} N² at {:.0} ns",
                self.rows.len(),
                f.time_ns(),
                f.aise(),
                b.aise(),
                b.time_ns()
            ),
            _ => format!("none of the {} points was measured (all failed)", self.rows.len()),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(n: usize, time_ns: f64, aise: f64) -> TradeRow {
        TradeRow {
            n,
            tol: None,
            max_sv: None,
            point: SearchPoint {
                c: 100.0,
                epsilon: 0.02,
                gamma: Some(30.0),
                cv_aise: aise,
                n_sv: 100.0,
                fit_seconds: 0.01,
                predict_ns: time_ns,
                failed: None,
            },
            held_out: None,
            on_front: false,
        }
    }

    fn table(rows: Vec<TradeRow>) -> TradeTable {
        let mut rows = rows;
        let front = pareto_front(&rows);
        rows.iter_mut().zip(front).for_each(|(r, f)| r.on_front = f);
        TradeTable {
            model: ModelKind::NeedlePuncture,
            capture_sha256: capture::sha256_hex(b"capture"),
            rows,
        }
    }

    #[test]
    fn the_front_holds_exactly_the_points_nothing_beats_on_both() {
        let mut failed = row(1, 5.0, 0.5);
        failed.point.failed = Some("no".into());
        let points = [
            row(1, 10.0, 5.0), // fastest: on
            row(1, 20.0, 2.0), // on
            row(1, 30.0, 2.0), // as accurate as the one before, slower: off
            row(1, 40.0, 1.0), // most accurate: on
            row(1, 25.0, 4.0), // beaten by (20, 2): off
            failed,            // failed: never on, and beats nothing
            row(1, 10.0, 5.0), // a tie with the first: both on
        ];
        assert_eq!(
            pareto_front(&points),
            [true, true, false, true, false, false, true]
        );
    }

    #[test]
    fn a_table_round_trips_through_its_file() {
        let mut failed = row(1000, f64::NAN, f64::NAN);
        failed.point.failed = Some("did not converge, \"gap\" 1e-3".into());
        let mut held = row(350, 700.0, 0.01);
        held.held_out = Some(HeldOut {
            aise: 0.0125,
            max_error_n: 0.9,
            peak_error_n: 0.2,
            predict_ns: 650.0,
            predict_f32_ns: 90.0,
        });
        held.tol = Some(1e-6);
        held.max_sv = Some(50);
        let t = table(vec![row(350, 500.0, 0.02), held, failed]);
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("trade.csv");
        t.write(&path).expect("write");
        let bytes = std::fs::read(&path).expect("read");
        let back = TradeTable::parse(&bytes, &path).expect("parse");
        assert_eq!(back.model, t.model);
        assert_eq!(back.capture_sha256, t.capture_sha256);
        assert_eq!(back.rows.len(), 3);
        assert_eq!(back.rows[..2], t.rows[..2]);
        assert_eq!(
            back.rows[2].point.failed.as_deref(),
            Some("did not converge,  gap  1e-3")
        );
        assert!(!back.rows[2].ok());
    }

    #[test]
    fn the_budget_picks_the_cheapest_point_that_meets_it_or_says_why_none_does() {
        let t = table(vec![
            row(350, 500.0, 0.020),
            row(350, 800.0, 0.012),
            row(1000, 900.0, 0.011),
            row(1000, 1200.0, 0.009),
            row(350, 850.0, 0.015), // beaten by the 800 ns point
        ]);
        let pick = |max_predict_ns, max_aise| {
            t.choose(&Budget {
                max_predict_ns,
                max_aise,
            })
        };
        let c = pick(Some(1000.0), Some(0.0115)).expect("a point");
        assert_eq!((c.row.n, c.row.time_ns()), (1000, 900.0));
        assert_eq!((c.within, c.measured), (1, 5));
        assert!(c.row.on_front);
        // Only a time limit: the fastest; only an accuracy limit: the cheapest accurate enough.
        assert_eq!(pick(Some(600.0), None).expect("fast").row.time_ns(), 500.0);
        assert_eq!(pick(None, Some(0.013)).expect("accurate").row.time_ns(), 800.0);
        // The cheapest point within a budget is on the front whatever the budget.
        for t_ns in [500.0, 700.0, 850.0, 1000.0, 2000.0] {
            for a in [0.01, 0.0115, 0.016, 0.03] {
                if let Ok(c) = pick(Some(t_ns), Some(a)) {
                    assert!(c.row.on_front, "{t_ns} {a}");
                }
            }
        }
        let why = pick(Some(600.0), Some(0.01)).expect_err("none");
        assert!(
            why.contains("none of the 5 measured points meets max_predict_ns = 600")
                && why.contains("the fastest takes 500 ns")
                && why.contains("the most accurate reaches 9.000e-3 N² at 1200 ns"),
            "{why}"
        );
    }

    #[test]
    fn a_bad_table_names_the_line_and_column() {
        let path = Path::new("trade.csv");
        let head = format!("{MAGIC} model=needle capture_sha256=ab\n{}\n", COLUMNS.join(","));
        let cases = [
            ("n,c\n".to_owned(), "line 1: not a trade table"),
            (format!("{MAGIC} capture_sha256=ab\n"), "no `model=`"),
            (
                format!("{MAGIC} model=needle capture_sha256=ab\nn,c\n"),
                "line 2: expected the columns",
            ),
            (head.clone(), "line 3: no points"),
            (
                format!("{head}350,1e2,2e-2,3e1,,,x,1,1,1,,,,,,true,\"\"\n"),
                "line 3, column `cv_aise`: `x` is not",
            ),
            (
                format!("{head}350,1e2,2e-2,3e1,,,1,1,1,,,,,,,true,\"\"\n"),
                "line 3, column `predict_ns`: empty",
            ),
            (
                format!("{head}350,1e2,2e-2,3e1,,,1,1,1,1,1,,,,,true,\"\"\n"),
                "all given or all empty",
            ),
            (
                format!("{head}350,1e2,2e-2,3e1,,,1,1,1,1,1,1,1,1,x,true,\"\"\n"),
                "column `test_predict_f32_ns`",
            ),
            (
                format!("{head}350,1e2,2e-2,3e1,,0,1,1,1,1,,,,,,true,\"\"\n"),
                "column `max_sv`",
            ),
            (
                format!("{head}350,1e2,2e-2,3e1,,,1,1,1,1,,,,,,yes,\"\"\n"),
                "column `on_front`",
            ),
            // Hyperparameters held to the rule a command line's and a scene's are.
            (
                format!("{head}350,1e-300,2e-2,3e1,,,1,1,1,1,,,,,,true,\"\"\n"),
                "line 3, column `c`: 1e-300: C must be in [1e-6, 1e15]",
            ),
            (
                format!("{head}350,1e2,2e-2,1e9,,,1,1,1,1,,,,,,true,\"\"\n"),
                "column `gamma`",
            ),
            (
                format!("{head}350,1e2,2e-2,3e1,2,,1,1,1,1,,,,,,true,\"\"\n"),
                "column `tol`",
            ),
        ];
        for (text, want) in cases {
            let err = TradeTable::parse(text.as_bytes(), path)
                .expect_err(want)
                .to_string();
            assert!(err.starts_with("trade.csv: line ") && err.contains(want), "{err}");
        }
    }
}

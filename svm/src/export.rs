//! libsvm's model text format, so `svm-predict` (and every libsvm binding) can run our models,
//! and libsvm's models can be checked against ours.
//!
//! The layout is the one libsvm's `svm_save_model` writes for an ε-SVR:
//!
//! ```text
//! svm_type epsilon_svr
//! kernel_type rbf            (linear | polynomial | rbf)
//! degree 3                   (polynomial only)
//! gamma 7.5                  (polynomial and rbf)
//! coef0 1                    (polynomial only)
//! nr_class 2                 (regression models are stored as two "classes")
//! total_sv 12
//! rho -0.1234                (libsvm's f(x) = Σ βᵢ K(xᵢ, x) − rho, so rho = −bias)
//! SV
//! 0.5 1:0.25 2:0.75          (βᵢ, then the support vector as 1-based index:value pairs)
//! ```
//!
//! Numbers are written in the shortest form that reads back to the same `f64` (libsvm itself
//! writes support vectors with only 8 significant digits, so its files do not round-trip;
//! ours do). The reader accepts what libsvm writes: sparse vectors (absent indices are 0),
//! `%.17g` numbers, `nu_svr` models (same decision function) and a `probA` line (the scale of
//! libsvm's optional Laplace error model, which prediction does not use).

use std::fmt;
use std::io::{BufRead, Write};

use super::error::SvmError;
use super::kernel::Kernel;
use super::model::SvrModel;

/// Writes `model` in libsvm's model text format.
///
/// A linear model that carries primal weights `w` is written as the single equivalent support
/// vector `w` with coefficient 1 (`K(w, x) = w·x`): libsvm would otherwise re-sum `Σ βᵢ xᵢ`,
/// which at large C cancels terms of size ~C and loses the digits the primal `w` keeps.
pub fn write_libsvm_model<W: Write>(model: &SvrModel, mut w: W) -> Result<(), SvmError> {
    check_exportable(model)?;
    if let (Kernel::Linear, Some(weights)) = (model.kernel, &model.weights) {
        let primal = SvrModel {
            kernel: Kernel::Linear,
            dim: model.dim,
            support_vectors: weights.clone(),
            coefficients: vec![1.0],
            bias: model.bias,
            weights: None,
        };
        return write_libsvm_model(&primal, w);
    }
    let mut header = String::from("svm_type epsilon_svr\n");
    match model.kernel {
        Kernel::Linear => header.push_str("kernel_type linear\n"),
        Kernel::Rbf { gamma } => {
            header.push_str("kernel_type rbf\n");
            header.push_str(&format!("gamma {}\n", Num(gamma)));
        }
        Kernel::Polynomial { gamma, coef0, degree } => {
            header.push_str("kernel_type polynomial\n");
            header.push_str(&format!(
                "degree {degree}\ngamma {}\ncoef0 {}\n",
                Num(gamma),
                Num(coef0)
            ));
        }
    }
    header.push_str(&format!(
        "nr_class 2\ntotal_sv {}\nrho {}\nSV\n",
        model.n_sv(),
        Num(-model.bias)
    ));
    w.write_all(header.as_bytes())?;
    let mut line = String::new();
    for i in 0..model.n_sv() {
        line.clear();
        line.push_str(&Num(model.coefficients[i]).to_string());
        for (k, v) in model.support_vector(i).iter().enumerate() {
            line.push_str(&format!(" {}:{}", k + 1, Num(*v)));
        }
        line.push('\n');
        w.write_all(line.as_bytes())?;
    }
    w.flush()?;
    Ok(())
}

/// [`write_libsvm_model`] into a string.
pub fn to_libsvm_string(model: &SvrModel) -> Result<String, SvmError> {
    let mut out = Vec::new();
    write_libsvm_model(model, &mut out)?;
    String::from_utf8(out).map_err(|e| SvmError::LibsvmExport(e.to_string()))
}

/// Reads a libsvm regression model; the input dimension is the largest index used (0 for a
/// model without support vectors, whose prediction is its bias for any input).
pub fn read_libsvm_model<R: BufRead>(r: R) -> Result<SvrModel, SvmError> {
    read_impl(r, None)
}

/// Reads a libsvm regression model of input dimension `dim` (needed when the last inputs are 0
/// in every support vector, which libsvm's sparse vectors do not write).
pub fn read_libsvm_model_with_dim<R: BufRead>(r: R, dim: usize) -> Result<SvrModel, SvmError> {
    read_impl(r, Some(dim))
}

/// Writes an `f64` in its shortest round-trip form (`1e-7`, `0.25`, `-3.0`), which libsvm's
/// `strtod` reads back exactly.
struct Num(f64);

impl fmt::Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut buffer = ryu::Buffer::new();
        f.write_str(buffer.format(self.0))
    }
}

fn check_exportable(model: &SvrModel) -> Result<(), SvmError> {
    let fail = |reason: String| Err(SvmError::LibsvmExport(reason));
    if model.support_vectors.len() != model.n_sv() * model.dim {
        return fail(format!(
            "{} support-vector values for {} coefficients of dimension {}",
            model.support_vectors.len(),
            model.n_sv(),
            model.dim
        ));
    }
    if model.dim == 0 && model.n_sv() > 0 {
        return fail("support vectors of dimension 0".to_owned());
    }
    let finite = |name: &str, v: f64| {
        if v.is_finite() {
            Ok(())
        } else {
            Err(SvmError::LibsvmExport(format!("{name} = {v} is not finite")))
        }
    };
    finite("bias", model.bias)?;
    if let Some(weights) = &model.weights {
        if model.kernel != Kernel::Linear {
            return fail(format!("primal weights with a {} kernel", model.kernel.name()));
        }
        if weights.len() != model.dim {
            return fail(format!(
                "{} primal weights for dimension {}",
                weights.len(),
                model.dim
            ));
        }
        if let Some(i) = weights.iter().position(|v| !v.is_finite()) {
            return fail(format!("primal weight {i} = {} is not finite", weights[i]));
        }
    }
    match model.kernel {
        Kernel::Linear => {}
        Kernel::Rbf { gamma } => finite("gamma", gamma)?,
        Kernel::Polynomial { gamma, coef0, degree } => {
            finite("gamma", gamma)?;
            finite("coef0", coef0)?;
            if i32::try_from(degree).is_err() {
                return fail(format!("degree {degree} exceeds libsvm's int"));
            }
        }
    }
    if let Some(i) = model.coefficients.iter().position(|v| !v.is_finite()) {
        return fail(format!(
            "coefficient {i} = {} is not finite",
            model.coefficients[i]
        ));
    }
    if let Some(i) = model.support_vectors.iter().position(|v| !v.is_finite()) {
        return fail(format!(
            "support vector {} element {} = {} is not finite",
            i / model.dim,
            i % model.dim + 1,
            model.support_vectors[i]
        ));
    }
    Ok(())
}

#[derive(Default)]
struct Header {
    svm_type: bool,
    kernel_type: Option<String>,
    kernel_line: usize,
    degree: Option<u32>,
    gamma: Option<(f64, usize)>,
    coef0: Option<f64>,
    nr_class: bool,
    total_sv: Option<usize>,
    rho: Option<f64>,
    prob_a: bool,
}

fn parse_f64(what: &str, text: &str, line: usize) -> Result<f64, SvmError> {
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(SvmError::LibsvmBadNumber {
            line,
            what: what.to_owned(),
            text: text.to_owned(),
            expected: "a finite number",
        }),
    }
}

fn parse_usize(what: &str, text: &str, line: usize) -> Result<usize, SvmError> {
    text.parse::<usize>().map_err(|_| SvmError::LibsvmBadNumber {
        line,
        what: what.to_owned(),
        text: text.to_owned(),
        expected: "a non-negative integer",
    })
}

fn one_value<'a>(key: &str, values: &[&'a str], line: usize) -> Result<&'a str, SvmError> {
    match values {
        [v] => Ok(v),
        _ => Err(SvmError::LibsvmValueCount {
            line,
            key: key.to_owned(),
            expected: 1,
            found: values.len(),
        }),
    }
}

fn read_impl<R: BufRead>(r: R, dim: Option<usize>) -> Result<SvrModel, SvmError> {
    let mut lines = r.lines().enumerate().map(|(i, l)| (i + 1, l));
    let mut h = Header::default();

    // Header, up to the `SV` line.
    let mut sv_line = None;
    for (no, text) in lines.by_ref() {
        let text = text?;
        let mut tokens = text.split_whitespace();
        let Some(key) = tokens.next() else { continue };
        let values: Vec<&str> = tokens.collect();
        let duplicate = |seen: bool| {
            if seen {
                Err(SvmError::LibsvmDuplicateKey {
                    line: no,
                    key: key.to_owned(),
                })
            } else {
                Ok(())
            }
        };
        match key {
            "svm_type" => {
                duplicate(h.svm_type)?;
                let t = one_value(key, &values, no)?;
                if t != "epsilon_svr" && t != "nu_svr" {
                    return Err(SvmError::LibsvmSvmType {
                        line: no,
                        svm_type: t.to_owned(),
                    });
                }
                h.svm_type = true;
            }
            "kernel_type" => {
                duplicate(h.kernel_type.is_some())?;
                let t = one_value(key, &values, no)?;
                if !matches!(t, "linear" | "polynomial" | "rbf") {
                    return Err(SvmError::LibsvmKernel {
                        line: no,
                        kernel: t.to_owned(),
                    });
                }
                h.kernel_type = Some(t.to_owned());
                h.kernel_line = no;
            }
            "degree" => {
                duplicate(h.degree.is_some())?;
                let text = one_value(key, &values, no)?;
                let d = text.parse::<i64>().map_err(|_| SvmError::LibsvmBadNumber {
                    line: no,
                    what: "degree".to_owned(),
                    text: text.to_owned(),
                    expected: "an integer",
                })?;
                match u32::try_from(d) {
                    Ok(d) if (1..=i32::MAX as u32).contains(&d) => h.degree = Some(d),
                    _ => {
                        return Err(SvmError::LibsvmParameter {
                            line: no,
                            name: "degree",
                            value: d as f64,
                            reason: "must be an integer between 1 and 2³¹ − 1",
                        });
                    }
                }
            }
            "gamma" => {
                duplicate(h.gamma.is_some())?;
                h.gamma = Some((parse_f64("gamma", one_value(key, &values, no)?, no)?, no));
            }
            "coef0" => {
                duplicate(h.coef0.is_some())?;
                h.coef0 = Some(parse_f64("coef0", one_value(key, &values, no)?, no)?);
            }
            "nr_class" => {
                duplicate(h.nr_class)?;
                let n = parse_usize("nr_class", one_value(key, &values, no)?, no)?;
                if n != 2 {
                    return Err(SvmError::LibsvmParameter {
                        line: no,
                        name: "nr_class",
                        value: n as f64,
                        reason: "a regression model has nr_class 2",
                    });
                }
                h.nr_class = true;
            }
            "total_sv" => {
                duplicate(h.total_sv.is_some())?;
                h.total_sv = Some(parse_usize("total_sv", one_value(key, &values, no)?, no)?);
            }
            "rho" => {
                duplicate(h.rho.is_some())?;
                if !h.nr_class {
                    return Err(SvmError::LibsvmOrder {
                        line: no,
                        key: "rho",
                        after: "nr_class",
                    });
                }
                h.rho = Some(parse_f64("rho", one_value(key, &values, no)?, no)?);
            }
            "probA" => {
                duplicate(h.prob_a)?;
                parse_f64("probA", one_value(key, &values, no)?, no)?;
                h.prob_a = true;
            }
            "SV" => {
                if !values.is_empty() {
                    return Err(SvmError::LibsvmValueCount {
                        line: no,
                        key: "SV".to_owned(),
                        expected: 0,
                        found: values.len(),
                    });
                }
                sv_line = Some(no);
                break;
            }
            other => {
                return Err(SvmError::LibsvmUnknownKey {
                    line: no,
                    key: other.to_owned(),
                });
            }
        }
    }
    let sv_line = sv_line.ok_or(SvmError::LibsvmMissing("an `SV` line"))?;
    let missing = |key| Err(SvmError::LibsvmMissingKey { line: sv_line, key });
    if !h.svm_type {
        return missing("svm_type");
    }
    let Some(kernel_type) = h.kernel_type else {
        return missing("kernel_type");
    };
    if !h.nr_class {
        return missing("nr_class");
    }
    let Some(total_sv) = h.total_sv else {
        return missing("total_sv");
    };
    let Some(rho) = h.rho else { return missing("rho") };
    let kernel = kernel_from_header(&kernel_type, h.kernel_line, h.degree, h.gamma, h.coef0)?;

    // Support vectors.
    let mut coefficients = Vec::with_capacity(total_sv.min(1 << 20));
    let mut rows: Vec<Vec<(usize, f64)>> = Vec::with_capacity(total_sv.min(1 << 20));
    let mut last_line = sv_line;
    for (no, text) in lines {
        let text = text?;
        last_line = no;
        let mut tokens = text.split_whitespace();
        let Some(first) = tokens.next() else { continue };
        if coefficients.len() == total_sv {
            return Err(SvmError::LibsvmTooManySupportVectors {
                line: no,
                declared: total_sv,
            });
        }
        coefficients.push(parse_f64("coefficient", first, no)?);
        let mut row = Vec::new();
        let mut previous = 0;
        for token in tokens {
            let (index, value) = token.split_once(':').ok_or_else(|| SvmError::LibsvmBadNode {
                line: no,
                text: token.to_owned(),
            })?;
            let index = index.parse::<usize>().map_err(|_| SvmError::LibsvmBadNode {
                line: no,
                text: token.to_owned(),
            })?;
            if index <= previous {
                return Err(SvmError::LibsvmIndexOrder {
                    line: no,
                    index,
                    previous,
                });
            }
            if let Some(dim) = dim
                && index > dim
            {
                return Err(SvmError::LibsvmIndexBeyondDim { line: no, index, dim });
            }
            row.push((index, parse_f64(&format!("value of index {index}"), value, no)?));
            previous = index;
        }
        rows.push(row);
    }
    if coefficients.len() != total_sv {
        return Err(SvmError::LibsvmTooFewSupportVectors {
            line: last_line,
            declared: total_sv,
            found: coefficients.len(),
        });
    }
    let dim = dim.unwrap_or_else(|| {
        rows.iter()
            .filter_map(|r| r.last().map(|&(i, _)| i))
            .max()
            .unwrap_or(0)
    });
    let mut support_vectors = vec![0.0; rows.len() * dim];
    for (i, row) in rows.iter().enumerate() {
        for &(index, value) in row {
            support_vectors[i * dim + index - 1] = value;
        }
    }
    Ok(SvrModel {
        kernel,
        dim,
        support_vectors,
        coefficients,
        bias: -rho,
        // libsvm stores support vectors only.
        weights: None,
    })
}

fn kernel_from_header(
    kernel_type: &str,
    kernel_line: usize,
    degree: Option<u32>,
    gamma: Option<(f64, usize)>,
    coef0: Option<f64>,
) -> Result<Kernel, SvmError> {
    let positive_gamma = || match gamma {
        Some((g, _)) if g > 0.0 => Ok(g),
        Some((g, line)) => Err(SvmError::LibsvmParameter {
            line,
            name: "gamma",
            value: g,
            reason: "must be positive",
        }),
        None => Err(SvmError::LibsvmMissingKey {
            line: kernel_line,
            key: "gamma",
        }),
    };
    Ok(match kernel_type {
        "linear" => Kernel::Linear,
        "rbf" => Kernel::Rbf {
            gamma: positive_gamma()?,
        },
        _ => Kernel::Polynomial {
            gamma: positive_gamma()?,
            // libsvm's defaults when the line is absent: coef0 0, degree 3.
            coef0: coef0.unwrap_or(0.0),
            degree: degree.unwrap_or(3),
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const FIXTURES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures/libsvm");

    /// A deterministic, irregular sequence in [−1, 1) (a Weyl sequence through a sine), so the
    /// fixture models have no structure a kernel bug could hide behind.
    fn wiggle(i: usize, salt: f64) -> f64 {
        ((i as f64 * 0.618_033_988_749_894_8 + salt).fract() * 2.0 - 1.0)
            * (1.0 + 0.3 * (i as f64 + salt).sin())
            / 1.3
    }

    /// The models whose exported text is committed under `fixtures/libsvm/` (with libsvm's
    /// predictions for them, made by `fixtures/libsvm/check_with_libsvm.py`).
    fn fixture_models() -> Vec<(&'static str, SvrModel)> {
        let model = |kernel, dim: usize, n: usize, salt: f64, bias| {
            let mut support_vectors: Vec<f64> = (0..n * dim).map(|i| wiggle(i, salt)).collect();
            // Explicit zeros must survive the trip (libsvm's own writer leaves them out).
            support_vectors[1] = 0.0;
            SvrModel {
                kernel,
                dim,
                support_vectors,
                coefficients: (0..n).map(|i| 3.0 * wiggle(i, salt + 0.5)).collect(),
                bias,
                weights: None,
            }
        };
        vec![
            (
                "rbf_2d",
                model(Kernel::Rbf { gamma: 7.5 }, 2, 24, 0.1, 0.123_456_789),
            ),
            (
                "polynomial_3d",
                model(
                    Kernel::Polynomial {
                        gamma: 0.5,
                        coef0: 1.25,
                        degree: 3,
                    },
                    3,
                    10,
                    0.2,
                    -2.5e-3,
                ),
            ),
            ("linear_2d", model(Kernel::Linear, 2, 6, 0.3, 4.0)),
        ]
    }

    /// Inputs at which the fixtures are evaluated: a grid over and beyond the support vectors.
    fn fixture_inputs(dim: usize) -> Vec<Vec<f64>> {
        (0..40)
            .map(|i| (0..dim).map(|k| 1.4 * wiggle(i * dim + k, 0.77)).collect())
            .collect()
    }

    fn read_fixture(name: &str) -> String {
        let path = format!("{FIXTURES}/{name}");
        std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
    }

    fn parse_rows(text: &str) -> Vec<Vec<f64>> {
        text.lines()
            .filter(|l| !l.trim().is_empty())
            .map(|l| l.split(',').map(|v| v.trim().parse().unwrap()).collect())
            .collect()
    }

    /// Regenerates the Rust side of the fixtures (model texts and inputs). Run it, then
    /// `fixtures/libsvm/check_with_libsvm.py`, when the fixture models change:
    /// `cargo test -p svm --lib write_libsvm_fixtures -- --ignored`.
    #[test]
    #[ignore = "writes fixtures; run by hand when they change"]
    fn write_libsvm_fixtures() {
        std::fs::create_dir_all(FIXTURES).unwrap();
        for (name, model) in fixture_models() {
            std::fs::write(
                format!("{FIXTURES}/{name}.model"),
                to_libsvm_string(&model).unwrap(),
            )
            .unwrap();
        }
        for dim in [2, 3] {
            let text: String = fixture_inputs(dim)
                .iter()
                .map(|row| {
                    row.iter()
                        .map(|v| Num(*v).to_string())
                        .collect::<Vec<_>>()
                        .join(",")
                        + "\n"
                })
                .collect();
            std::fs::write(format!("{FIXTURES}/inputs_{dim}d.csv"), text).unwrap();
        }
    }

    #[test]
    fn export_writes_libsvms_layout() {
        let m = SvrModel {
            kernel: Kernel::Polynomial {
                gamma: 0.5,
                coef0: 1.0,
                degree: 2,
            },
            dim: 2,
            support_vectors: vec![0.25, -1e-7, 3.0, 0.0],
            coefficients: vec![1.5, -1.5],
            bias: 0.75,
            weights: None,
        };
        assert_eq!(
            to_libsvm_string(&m).unwrap(),
            "svm_type epsilon_svr\nkernel_type polynomial\ndegree 2\ngamma 0.5\ncoef0 1.0\nnr_class 2\n\
             total_sv 2\nrho -0.75\nSV\n1.5 1:0.25 2:-1e-7\n-1.5 1:3.0 2:0.0\n"
        );
        let linear = SvrModel {
            kernel: Kernel::Linear,
            ..m
        };
        let text = to_libsvm_string(&linear).unwrap();
        assert!(
            text.starts_with("svm_type epsilon_svr\nkernel_type linear\nnr_class 2\n"),
            "{text}"
        );
    }

    #[test]
    fn round_trip_is_bit_exact() {
        for (name, model) in fixture_models() {
            let text = to_libsvm_string(&model).unwrap();
            let back = read_libsvm_model(text.as_bytes()).unwrap();
            assert_eq!(back, model, "{name}");
        }
    }

    #[test]
    fn exporter_output_is_the_committed_fixture() {
        for (name, model) in fixture_models() {
            assert_eq!(
                to_libsvm_string(&model).unwrap(),
                read_fixture(&format!("{name}.model")),
                "{name}: regenerate with write_libsvm_fixtures and check_with_libsvm.py"
            );
        }
    }

    #[test]
    fn our_predictions_match_libsvm_on_exported_models() {
        for (name, model) in fixture_models() {
            let inputs = parse_rows(&read_fixture(&format!("inputs_{}d.csv", model.dim)));
            assert_eq!(
                inputs,
                fixture_inputs(model.dim),
                "{name}: inputs fixture is stale"
            );
            let libsvm = parse_rows(&read_fixture(&format!("{name}.libsvm_predictions")));
            assert_eq!(libsvm.len(), inputs.len(), "{name}");
            for (x, expected) in inputs.iter().zip(&libsvm) {
                let ours = model.predict(x);
                let want = expected[0];
                assert!(
                    (ours - want).abs() <= 1e-12 * want.abs().max(1.0),
                    "{name} at {x:?}: ours {ours}, libsvm {want}"
                );
            }
        }
    }

    #[test]
    fn models_written_by_libsvm_import_and_predict_like_libsvm() {
        // Trained and saved by libsvm itself (sparse vectors, `%.8g` support vectors), then
        // reloaded by libsvm to make the predictions, so both sides use the same rounded file.
        let model = read_libsvm_model(read_fixture("libsvm_trained_rbf.model").as_bytes()).unwrap();
        assert_eq!(model.dim, 2);
        assert!(matches!(model.kernel, Kernel::Rbf { gamma } if gamma == 10.0));
        let inputs = parse_rows(&read_fixture("inputs_2d.csv"));
        let libsvm = parse_rows(&read_fixture("libsvm_trained_rbf.libsvm_predictions"));
        assert_eq!(libsvm.len(), inputs.len());
        for (x, expected) in inputs.iter().zip(&libsvm) {
            let (ours, want) = (model.predict(x), expected[0]);
            assert!(
                (ours - want).abs() <= 1e-12 * want.abs().max(1.0),
                "at {x:?}: ours {ours}, libsvm {want}"
            );
        }
    }

    #[test]
    fn sparse_vectors_fill_zeros_and_dimension_can_be_forced() {
        let text = "svm_type nu_svr\nkernel_type rbf\ngamma 2\nnr_class 2\ntotal_sv 2\nrho 0.5\nprobA 0.1\nSV\n\
                    0.75 2:1.5\n-0.25 1:-1 3:2e-1 \n";
        let m = read_libsvm_model(text.as_bytes()).unwrap();
        assert_eq!(m.dim, 3);
        assert_eq!(m.support_vectors, vec![0.0, 1.5, 0.0, -1.0, 0.0, 0.2]);
        assert_eq!((m.coefficients.clone(), m.bias), (vec![0.75, -0.25], -0.5));
        let wide = read_libsvm_model_with_dim(text.as_bytes(), 5).unwrap();
        assert_eq!(wide.dim, 5);
        assert_eq!(wide.support_vector(1), &[-1.0, 0.0, 0.2, 0.0, 0.0]);
        assert!(
            (wide.predict(&[0.0; 5]) - (0.75 * (-2.0f64 * 2.25).exp() - 0.25 * (-2.0f64 * 1.04).exp() - 0.5))
                .abs()
                < 1e-15
        );
        assert!(matches!(
            read_libsvm_model_with_dim(text.as_bytes(), 2),
            Err(SvmError::LibsvmIndexBeyondDim {
                line: 10,
                index: 3,
                dim: 2
            })
        ));
    }

    fn parse_err(text: &str) -> SvmError {
        match read_libsvm_model(text.as_bytes()) {
            Err(e) if e.line().is_some() => e,
            other => panic!("expected a parse error, got {other:?}"),
        }
    }

    #[test]
    fn malformed_files_name_the_line_and_the_problem() {
        let good =
            "svm_type epsilon_svr\nkernel_type rbf\ngamma 2\nnr_class 2\ntotal_sv 1\nrho 0.5\nSV\n1 1:0.5\n";
        assert!(read_libsvm_model(good.as_bytes()).is_ok());
        let cases: &[(&str, &str, usize)] = &[
            ("svm_type epsilon_svr", "svm_type c_svc", 1),
            ("kernel_type rbf", "kernel_type sigmoid", 2),
            ("gamma 2", "gamma -2", 3),
            ("gamma 2", "gamma two", 3),
            ("gamma 2", "gamma nan", 3),
            ("nr_class 2", "nr_class 3", 4),
            ("total_sv 1", "total_sv 2", 8),
            ("total_sv 1", "total_sv 0", 8),
            ("rho 0.5", "rho", 6),
            ("rho 0.5", "label 1 -1", 6),
            ("1 1:0.5", "1 0:0.5", 8),
            ("1 1:0.5", "1 2:0.5 1:0.1", 8),
            ("1 1:0.5", "1 1=0.5", 8),
            ("1 1:0.5", "x 1:0.5", 8),
            ("1 1:0.5", "1 1:inf", 8),
            ("gamma 2\n", "gamma 2\ngamma 3\n", 4),
        ];
        for &(from, to, line) in cases {
            let text = good.replacen(from, to, 1);
            let err = parse_err(&text);
            assert_eq!(err.line(), Some(line), "{to}: {err}");
            // Every message names the line and what is wrong with it.
            let message = err.to_string();
            let what = message.strip_prefix(&format!("line {line}: "));
            assert!(what.is_some_and(|w| !w.is_empty()), "{message}");
        }
        assert_eq!(
            parse_err(&good.replace("gamma 2\n", "")),
            SvmError::LibsvmMissingKey {
                line: 2,
                key: "gamma"
            }
        );
        assert_eq!(
            parse_err(&good.replace("total_sv 1\n", "")),
            SvmError::LibsvmMissingKey {
                line: 6,
                key: "total_sv"
            }
        );
        assert_eq!(
            parse_err("svm_type epsilon_svr\nkernel_type linear\nrho 1\n"),
            SvmError::LibsvmOrder {
                line: 3,
                key: "rho",
                after: "nr_class"
            }
        );
        assert!(matches!(
            read_libsvm_model(good.split("total_sv").next().unwrap().as_bytes()),
            Err(SvmError::LibsvmMissing(_))
        ));
    }

    #[test]
    fn a_linear_model_with_primal_weights_exports_them_as_one_support_vector() {
        // Coefficients that cancel to w = (0.5, −0.25) only approximately; the primal weights are
        // what the model predicts with, so they are what libsvm must see.
        let m = SvrModel {
            kernel: Kernel::Linear,
            dim: 2,
            support_vectors: vec![1.0, 0.0, 1.0 + 1e-9, -1e-6],
            coefficients: vec![-1e6, 1e6],
            bias: 0.125,
            weights: Some(vec![0.5, -0.25]),
        };
        let text = to_libsvm_string(&m).unwrap();
        assert!(
            text.ends_with("total_sv 1\nrho -0.125\nSV\n1.0 1:0.5 2:-0.25\n"),
            "{text}"
        );
        let back = read_libsvm_model(text.as_bytes()).unwrap();
        for x in [[1.0, 2.0], [-3.0, 0.5], [1e3, -1e3]] {
            assert_eq!(back.predict(&x), m.predict(&x));
        }
        let bad = SvrModel {
            weights: Some(vec![0.5]),
            ..m
        };
        assert!(matches!(to_libsvm_string(&bad), Err(SvmError::LibsvmExport(_))));
    }

    #[test]
    fn inconsistent_models_are_not_exported() {
        let mut m = fixture_models().remove(0).1;
        m.support_vectors.pop();
        assert!(matches!(to_libsvm_string(&m), Err(SvmError::LibsvmExport(_))));
        let mut m = fixture_models().remove(0).1;
        m.coefficients[3] = f64::NAN;
        let err = to_libsvm_string(&m).unwrap_err().to_string();
        assert!(err.contains("coefficient 3"), "{err}");
        let mut m = fixture_models().remove(0).1;
        m.kernel = Kernel::Rbf { gamma: f64::INFINITY };
        assert!(matches!(to_libsvm_string(&m), Err(SvmError::LibsvmExport(_))));
    }
}

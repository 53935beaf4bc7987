//! The one entry to identification: each model kind to the function that identifies it
//! (Li & Bi's three in `identification`, the phase-aware needle in `phase_identification`).

use capture::{Capture, kind};

use crate::contact_identification::{hard, soft};
use crate::error::IdentifyError;
use crate::identification::{FitLimits, Identified, IdentifyOptions, Job, model_column};
use crate::model_file::{ModelBody, ModelKind};
use crate::needle_identification::needle;
use crate::outliers::{force_noise_n, screen};
use crate::phase_identification::needle_phases;
use crate::phases::WithdrawalSource;
use crate::plausibility::Plausibility;
use crate::punctures::PunctureParams;

/// Identifies `options.kind` from `train`, evaluating on `test` when given (else on `train`).
pub fn identify(
    train: &Capture,
    test: Option<&Capture>,
    options: &IdentifyOptions,
) -> Result<Identified, IdentifyError> {
    identify_with(train, test, options, &FitLimits::default())
}

/// [`identify`] with every SVR fit under `limits` (tolerance, time budget, progress).
///
/// An insertion capture is first screened for gross outliers ([`crate::OutlierScreen`]): the
/// rows found are left out of every fit and every metric (the baselines' too) unless
/// `options.keep_outliers`, and the report lists them either way.
pub fn identify_with(
    train: &Capture,
    test: Option<&Capture>,
    options: &IdentifyOptions,
    limits: &FitLimits<'_>,
) -> Result<Identified, IdentifyError> {
    Plausibility::check_hyperparameters(options.c, options.epsilon, options.gamma)
        .map_err(|(name, value, reason)| IdentifyError::InvalidParameter { name, value, reason })?;
    let needle_kind = matches!(options.kind, ModelKind::NeedlePuncture | ModelKind::NeedlePhases);
    let mut screens = Vec::new();
    let (train_kept, test_kept) = if needle_kind {
        let mut screened = |c: &Capture| -> Result<Capture, IdentifyError> {
            let force = c.column(kind::AXIAL_FORCE_N)?;
            let threshold_n = PunctureParams::default().threshold_n(force_noise_n(force));
            let screen = screen(c.source(), c.time(), force, threshold_n, options.keep_outliers);
            let drop: Vec<usize> = screen.rows.iter().map(|o| o.row).collect();
            let kept = if options.keep_outliers || drop.is_empty() {
                c.clone()
            } else {
                c.without_rows(&drop)?
            };
            screens.push(screen);
            Ok(kept)
        };
        (Some(screened(train)?), test.map(&mut screened).transpose()?)
    } else {
        (None, None)
    };
    let (train, test) = match &train_kept {
        Some(t) => (t, test_kept.as_ref()),
        None => (train, test),
    };
    let job = Job {
        train,
        test,
        options,
        limits,
    };
    let identified = match options.kind {
        ModelKind::HardFriction => hard(&job),
        ModelKind::SoftFriction => soft(&job),
        ModelKind::NeedlePuncture => needle(&job),
        ModelKind::NeedlePhases => needle_phases(&job),
    };
    // Every SVR trains on the training capture: a failed fit names it.
    let mut identified = identified.map_err(|e| match e {
        IdentifyError::Svr { what, source } => IdentifyError::Svr {
            what: format!("{what} on {}", train.source().display()),
            source,
        },
        other => other,
    })?;
    if options.kind == ModelKind::NeedlePhases {
        // Kept outliers are fitted, but the forces a tissue model answers for are the others.
        let kept: &[crate::Outlier] = match screens.first() {
            Some(s) if s.kept => &s.rows,
            _ => &[],
        };
        check_in_range(&identified, train, kept)?;
    }
    let report = &mut identified.report;
    for s in screens.iter().filter(|s| !s.rows.is_empty()) {
        let rows: Vec<String> = s
            .rows
            .iter()
            .take(5)
            .map(|o| format!("row {} ({:.3} N)", o.row, o.force_n))
            .collect();
        report.warnings.push(format!(
            "{}: {} gross outlier(s) (more than {:.3} N off both neighbours): {}{}; {}",
            s.capture.display(),
            s.rows.len(),
            s.threshold_n,
            rows.join(", "),
            if s.rows.len() > 5 { ", …" } else { "" },
            if s.kept {
                "kept in the fit (--keep-outliers)"
            } else {
                "left out of every fit and metric"
            }
        ));
    }
    report.outliers = screens;
    if let ModelBody::Phases(p) = &identified.model.body {
        identified.report.warnings.extend(phase_warnings(p));
    }
    Ok(identified)
}

/// How far a phase model's own force along its training capture may leave the range of the
/// forces measured there, as a fraction of that range: the force a tissue model renders comes
/// from the tissue, so a model that goes far past everything measured is wrong, not bold. (The
/// phase laws are least squares, which one gross sample can pull anywhere; a smooth ε-SVR's
/// loss is linear beyond its tube, so no sample pulls it by more than C, and its fit is
/// certified by its duality gap.)
pub const PLAUSIBLE_RANGE_MARGIN: f64 = 0.5;

/// Refuses a phase model whose force along its own training capture (in tissue, rendered as
/// the haptic thread renders it) leaves the
/// measured forces' range (outside the `outliers`) by more than [`PLAUSIBLE_RANGE_MARGIN`] of
/// that range.
fn check_in_range(
    identified: &Identified,
    train: &Capture,
    outliers: &[crate::Outlier],
) -> Result<(), IdentifyError> {
    let model = &identified.model;
    let depth = model_column(train, kind::DEPTH_M)?;
    let velocity = model_column(train, kind::VELOCITY_MPS)?;
    let force = train.column(kind::AXIAL_FORCE_N)?;
    let predicted: Vec<f64> = match &model.body {
        ModelBody::Phases(p) => p.simulate(&depth, &velocity).iter().map(|s| s.force_n).collect(),
        _ => return Ok(()),
    };
    let rows = || (0..depth.len()).filter(|&i| depth[i] > 0.0 && !outliers.iter().any(|o| o.row == i));
    let span = |x: &dyn Fn(usize) -> f64| {
        rows().fold([f64::INFINITY, f64::NEG_INFINITY], |[lo, hi], i| {
            [lo.min(x(i)), hi.max(x(i))]
        })
    };
    let measured = span(&|i| force[i]);
    let rendered = span(&|i| predicted[i]);
    if !(measured[0].is_finite() && rendered[0].is_finite()) {
        return Ok(());
    }
    let margin_n = PLAUSIBLE_RANGE_MARGIN * (measured[1] - measured[0]);
    if rendered[0] < measured[0] - margin_n || rendered[1] > measured[1] + margin_n {
        return Err(IdentifyError::Data {
            path: train.source().to_owned(),
            reason: format!(
                "the identified {} model renders {:.3} to {:.3} N along its own training capture, \
                 beyond the measured {:.3} to {:.3} N by more than {:.0} % of that range: an \
                 absurd model is not written (look for outliers the screen did not take, or a \
                 record too short for the model)",
                model.kind.short_name(),
                rendered[0],
                rendered[1],
                measured[0],
                measured[1],
                100.0 * PLAUSIBLE_RANGE_MARGIN
            ),
        });
    }
    Ok(())
}

/// What a phase model could not learn from its capture.
fn phase_warnings(p: &crate::PhaseModel) -> Vec<String> {
    let mut out = Vec::new();
    if p.withdrawal_source != WithdrawalSource::Measured {
        out.push(format!("withdrawal law {}", p.withdrawal_source.describe()));
    }
    for (k, l) in p.layers.iter().enumerate() {
        let t = &l.threshold;
        if t.coefficients.len() == 1 && t.speed_mps[1] - t.speed_mps[0] <= 0.1 * t.speed_mps[1].abs() {
            out.push(format!(
                "layer {}: its puncture was measured at one speed ({:.2} mm/s): how it moves with \
                 speed is unknown, so the model gives it at {:.2} mm of deflection at every speed",
                k + 1,
                0.5 * (t.speed_mps[0] + t.speed_mps[1]) * 1e3,
                t.deflection_m(t.speed_mps[0]) * 1e3
            ));
        }
    }
    out
}

//! The one entry to identification: each model kind to the function that identifies it
//! (Li & Bi's three in `identification`, the phase-aware needle in `phase_identification`).

use capture::Capture;

use crate::contact_identification::{hard, soft};
use crate::error::IdentifyError;
use crate::identification::{FitLimits, Identified, IdentifyOptions};
use crate::model_file::ModelKind;
use crate::needle_identification::needle;
use crate::phase_identification::needle_phases;

/// Identifies `options.kind` from `train`, evaluating on `test` when given (else on `train`).
pub fn identify(
    train: &Capture,
    test: Option<&Capture>,
    options: &IdentifyOptions,
) -> Result<Identified, IdentifyError> {
    identify_with(train, test, options, &FitLimits::default())
}

/// [`identify`] with every SVR fit under `limits` (tolerance, time budget, progress).
pub fn identify_with(
    train: &Capture,
    test: Option<&Capture>,
    options: &IdentifyOptions,
    limits: &FitLimits<'_>,
) -> Result<Identified, IdentifyError> {
    let identified = match options.kind {
        ModelKind::HardFriction => hard(train, test, options, limits),
        ModelKind::SoftFriction => soft(train, test, options, limits),
        ModelKind::NeedlePuncture => needle(train, test, options, limits),
        ModelKind::NeedlePhases => needle_phases(train, test, options, limits),
    };
    // Every SVR trains on the training capture: a failed fit names it.
    identified.map_err(|e| match e {
        IdentifyError::Svr { what, source } => IdentifyError::Svr {
            what: format!("{what} on {}", train.source().display()),
            source,
        },
        other => other,
    })
}

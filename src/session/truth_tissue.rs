//! Which simulated tissue a needle model renders, when it renders one: only then can a session
//! compare what the trainee felt with the tissue's own punctures and forces. The model's
//! capture says so when palpus's own generator wrote it (`protocol=li_bi_needle` with
//! `tissue=…`), or when a session on such a model recorded it (`truth_tissue=…`, written by
//! `palpus run --record`). A model from anything else (a rig's logs, the independent corpus,
//! whatever its `tissue` says) has no simulated truth, and the report compares it with none.

use std::io::BufReader;
use std::path::Path;

use capture::CaptureReader;
use identify::ModelFile;
use sim::li_bi::NeedleTissueKind;

/// The metadata key a recording names its model's simulated tissue with.
pub const TRUTH_KEY: &str = "truth_tissue";

/// The simulated tissue of the capture at `path`, if it names one as above.
pub fn of_capture(path: &Path) -> Option<NeedleTissueKind> {
    let file = std::fs::File::open(path).ok()?;
    let reader = CaptureReader::new(BufReader::new(file), path, None).ok()?;
    let meta = reader.metadata();
    match meta.get("protocol")? {
        "li_bi_needle" => NeedleTissueKind::named(meta.get("tissue")?),
        "palpus_run" => NeedleTissueKind::named(meta.get(TRUTH_KEY)?),
        _ => None,
    }
}

/// The simulated tissue of `model`: of `capture` (the scene's, when it identifies the model
/// from one), else of the capture the model file says it was trained on.
pub fn of_model(model: &ModelFile, capture: Option<&Path>) -> Option<NeedleTissueKind> {
    match capture {
        Some(path) => of_capture(path),
        None => model.training.first().and_then(|c| of_capture(&c.path)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_generators_and_its_recordings_tissues_are_truths() {
        let dir = tempfile::tempdir().expect("dir");
        let write = |name: &str, meta: &str| {
            let path = dir.path().join(name);
            std::fs::write(
                &path,
                format!(
                    "# palpus-capture format=1 kind=insertion device=x rate_hz=100 units=si {meta}\n\
                     time_s,depth_m,velocity_mps,axial_force_n\n0,0,0,0\n0.01,0,0,0\n"
                ),
            )
            .expect("write");
            path
        };
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        assert_eq!(
            of_capture(&root.join("assets/captures/li_bi/needle_train.csv")),
            Some(NeedleTissueKind::BovineLiver)
        );
        // The independent corpus names a bovine liver of its own: not the simulator's.
        assert_eq!(
            of_capture(&root.join("assets/captures/needle_corpus/one_speed_train.csv")),
            None
        );
        let phantom = write("p.csv", "protocol=li_bi_needle tissue=layered_phantom");
        assert_eq!(of_capture(&phantom), Some(NeedleTissueKind::LayeredPhantom));
        let recorded = write("r.csv", "protocol=palpus_run truth_tissue=bovine_liver");
        assert_eq!(of_capture(&recorded), Some(NeedleTissueKind::BovineLiver));
        assert_eq!(of_capture(&write("u.csv", "protocol=palpus_run")), None);
        assert_eq!(
            of_capture(&write("k.csv", "protocol=li_bi_needle tissue=kidney")),
            None
        );
        assert_eq!(of_capture(&dir.path().join("missing.csv")), None);
    }
}

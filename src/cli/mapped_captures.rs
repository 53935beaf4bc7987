//! Researchers' logs read directly by `recognize train|eval|cv`, through the same column map
//! as `palpus import` (which imports them one by one).

use std::path::PathBuf;

use anyhow::Context;
use capture::CaptureKind;
use capture::sha256_hex;
use capture::{ColumnMap, ImportSpec, import_csv};
use clap::Args;
use recognize::LabelledCapture;

use super::meta_arg::parse_meta;

/// `recognize train|eval` reading researchers' logs directly, through the same column map as
/// `palpus import`.
#[derive(Debug, Args)]
pub(crate) struct MappedCaptures {
    /// Read the captures as CSV logs through this column map (as `palpus import --map`)
    /// instead of as palpus captures.
    #[arg(long, value_name = "SPEC")]
    map: Option<String>,
    /// With --map: resample the logs to this rate, Hz.
    #[arg(long, value_name = "HZ", requires = "map")]
    rate_hz: Option<f64>,
    /// With --map: the logs' rate, Hz, when they have no time column.
    #[arg(long, value_name = "HZ", requires = "map")]
    input_rate_hz: Option<f64>,
    /// With --map: metadata for every log, repeatable. `{dir}` and `{stem}` in a value stand
    /// for the log's folder name and file name without extension, so logs laid out as
    /// `SURFACE/RUN.csv` are labelled by `--meta surface={dir}`.
    #[arg(long = "meta", value_name = "KEY=VALUE", value_parser = parse_meta, requires = "map")]
    meta: Vec<(String, String)>,
}

impl MappedCaptures {
    /// Reads `paths` as labelled rubbing captures: palpus captures, or logs through the map,
    /// resampled to `--rate-hz`, else to `default_rate_hz` (a recognizer's own rate) if given.
    pub(crate) fn read(
        &self,
        paths: &[PathBuf],
        default_rate_hz: Option<f64>,
    ) -> anyhow::Result<Vec<LabelledCapture>> {
        let Some(spec) = &self.map else {
            return paths
                .iter()
                .map(|p| LabelledCapture::read(p).with_context(|| format!("reading capture {}", p.display())))
                .collect();
        };
        let map = ColumnMap::parse(spec)?;
        paths
            .iter()
            .map(|p| {
                let name = |s: Option<&std::ffi::OsStr>| {
                    s.map(|s| s.to_string_lossy().into_owned()).unwrap_or_default()
                };
                let (dir, stem) = (name(p.parent().and_then(|d| d.file_name())), name(p.file_stem()));
                let spec = ImportSpec {
                    kind: CaptureKind::Rubbing,
                    map: map.clone(),
                    rate_hz: self.rate_hz.or(default_rate_hz),
                    input_rate_hz: self.input_rate_hz,
                    device: "imported".into(),
                    metadata: self
                        .meta
                        .iter()
                        .map(|(k, v)| (k.clone(), v.replace("{dir}", &dir).replace("{stem}", &stem)))
                        .collect(),
                    ..ImportSpec::new(CaptureKind::Rubbing, map.clone())
                };
                let capture = import_csv(p, &spec)?;
                let bytes = std::fs::read(p).with_context(|| format!("reading {}", p.display()))?;
                Ok(LabelledCapture::new(capture, p, sha256_hex(&bytes))?)
            })
            .collect()
    }
}

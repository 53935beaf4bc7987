//! Model resolution: the models a scene's drawn objects need, loaded from model files or
//! identified from captures on demand and cached.
//!
//! Every model, from a file, the cache or a fit, must be one the device can render: its
//! output over its own input range (the box the force laws clamp inputs to) stays within the
//! device's force limit, and the force law builds from it. Both are checked here, at load,
//! with the file named, so a corrupted or absurd model never reaches the haptic thread.
//!
//! The cache key is a SHA-256 of the model kind, the training capture's bytes and the
//! hyperparameters, so changing either re-identifies and nothing stale is ever served. Every
//! file goes through one reader (`Sources`), which is how the tests prove that a model no
//! object references is never opened.

use std::collections::BTreeSet;
use std::io::BufReader;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};

use capture::{Capture, CaptureKind};
use identify::{FitLimits, IdentifyOptions, ModelFile, ModelKind, identify_with};
use sha2::{Digest, Sha256};

use crate::scene::{ModelBudget, ModelRole, ModelSource, Scene};
use crate::trade::{Budget, TradeTable};
use capture::sha256_hex;

/// Bumped when identification changes in a way that makes cached models stale.
const CACHE_VERSION: &str = "palpus-model-cache 1";

/// Why a model could not be resolved.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    /// A file could not be read.
    #[error("model `{model}`: reading {}: {source}", path.display())]
    Read {
        /// The scene's name for the model.
        model: String,
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The capture is not a valid capture of the kind needed.
    #[error("model `{model}`: {source}")]
    Capture {
        /// The scene's name for the model.
        model: String,
        /// Why (boxed, as every large error here: errors are rare and results many).
        source: Box<capture::CaptureError>,
    },
    /// The model file is not valid.
    #[error("model `{model}`: {source}")]
    File {
        /// The scene's name for the model.
        model: String,
        /// Why (boxed).
        source: Box<identify::IdentifyError>,
    },
    /// The model file models something else.
    #[error("model `{model}`: {} holds a {found} model, the scene says {expected}", path.display())]
    WrongKind {
        /// The scene's name for the model.
        model: String,
        /// The file.
        path: PathBuf,
        /// What the scene says.
        expected: ModelKind,
        /// What the file holds.
        found: ModelKind,
    },
    /// Identification failed.
    #[error("model `{model}`: identifying from {}: {source}", path.display())]
    Identify {
        /// The scene's name for the model.
        model: String,
        /// The capture.
        path: PathBuf,
        /// Why (boxed: identification errors are large and rare).
        source: Box<identify::IdentifyError>,
    },
    /// The model cannot be proved within what the device renders (see
    /// [`identify::ModelFile::certify`]).
    #[error("model `{model}`: {}: {source}", path.display())]
    Unsafe {
        /// The scene's name for the model.
        model: String,
        /// The model file (or the capture it was identified from).
        path: PathBuf,
        /// Which part, where and why (boxed: it names places and is rare).
        source: Box<identify::BoundViolation>,
    },
    /// A force law cannot be built from the model.
    #[error("model `{model}`: {}: {source}", path.display())]
    Law {
        /// The scene's name for the model.
        model: String,
        /// The model file (or the capture it was identified from).
        path: PathBuf,
        /// Why (boxed: the haptics error is large and this one rare).
        source: Box<haptics::HapticsError>,
    },
    /// The scene's budget cannot pick a point from its trade table.
    #[error("model `{model}`: budget from {}: {reason}", path.display())]
    Budget {
        /// The scene's name for the model.
        model: String,
        /// The trade table.
        path: PathBuf,
        /// Why.
        reason: String,
    },
    /// The cache could not be written.
    #[error("model `{model}`: writing the cache: {source}")]
    Cache {
        /// The scene's name for the model.
        model: String,
        /// Why (boxed).
        source: Box<identify::IdentifyError>,
    },
}

/// Where a resolved model came from.
#[derive(Debug, Clone, PartialEq)]
pub enum Origin {
    /// A model file named by the scene.
    File(PathBuf),
    /// The cache, identified earlier from the same capture bytes and hyperparameters.
    Cached(PathBuf),
    /// Identified now (and cached at the path).
    Identified {
        /// Where it was cached.
        cached: PathBuf,
        /// How long fitting took.
        seconds: f64,
    },
}

/// A model ready for a force law.
#[derive(Debug, Clone)]
pub struct ResolvedModel {
    /// The scene's name for it.
    pub name: String,
    /// What the material uses it for.
    pub role: ModelRole,
    /// The model.
    pub model: ModelFile,
    /// Where it came from.
    pub origin: Origin,
    /// The point a scene's budget picked, when it gave one.
    pub budget: Option<BudgetChoice>,
}

/// The point of a measured trade that a scene's budget picked, as the run report shows it.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct BudgetChoice {
    /// The trade table.
    pub front: PathBuf,
    /// The budget's time limit, ns.
    pub max_predict_ns: Option<f64>,
    /// The budget's AISE limit, N².
    pub max_aise: Option<f64>,
    /// The point's training size, C, ε and γ.
    pub n: usize,
    /// C.
    pub c: f64,
    /// ε.
    pub epsilon: f64,
    /// γ.
    pub gamma: Option<f64>,
    /// The solver tolerance it was measured with (`None`: the default).
    pub tol: Option<f64>,
    /// Its support-vector budget (`None`: none).
    pub max_sv: Option<usize>,
    /// Its measured time per prediction, ns.
    pub predict_ns: f64,
    /// Its measured AISE, N².
    pub aise: f64,
    /// Points within the budget.
    pub within: usize,
    /// Points measured.
    pub measured: usize,
}

impl std::fmt::Display for BudgetChoice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let budget = Budget {
            max_predict_ns: self.max_predict_ns,
            max_aise: self.max_aise,
        };
        let gamma = self.gamma.map_or(String::new(), |g| format!(", γ {g:e}"));
        let tol = self.tol.map_or(String::new(), |t| format!(", tolerance {t:e}"));
        let max_sv = self
            .max_sv
            .map_or(String::new(), |k| format!(", at most {k} support vectors"));
        write!(
            f,
            "for {budget}: n {}, C {:e}, ε {:e}{gamma}{tol}{max_sv}, measured {:.0} ns per prediction at an AISE of {:.3e} N², the cheapest of {} of {} points in {}",
            self.n,
            self.c,
            self.epsilon,
            self.predict_ns,
            self.aise,
            self.within,
            self.measured,
            self.front.display()
        )
    }
}

/// Reads a whole file.
type Reader<'a> = Box<dyn FnMut(&Path) -> std::io::Result<Vec<u8>> + 'a>;

/// Every file read on the way to the models (the tests' witness), and the reader.
pub struct Sources<'a> {
    read: Reader<'a>,
    opened: BTreeSet<PathBuf>,
}

impl std::fmt::Debug for Sources<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Sources").field("opened", &self.opened).finish()
    }
}

impl Default for Sources<'_> {
    fn default() -> Self {
        Self::new(|p| std::fs::read(p))
    }
}

impl<'a> Sources<'a> {
    /// Reads files with `read`.
    pub fn new(read: impl FnMut(&Path) -> std::io::Result<Vec<u8>> + 'a) -> Self {
        Self {
            read: Box::new(read),
            opened: BTreeSet::new(),
        }
    }

    fn read(&mut self, path: &Path) -> std::io::Result<Vec<u8>> {
        self.opened.insert(path.to_owned());
        (self.read)(path)
    }

    /// The bytes of `path`, a source of the scene's model `model`.
    fn read_model_source(&mut self, model: &str, path: &Path) -> Result<Vec<u8>, ModelError> {
        self.read(path).map_err(|e| ModelError::Read {
            model: model.into(),
            path: path.to_owned(),
            source: e,
        })
    }

    /// Every path read so far.
    pub fn opened(&self) -> &BTreeSet<PathBuf> {
        &self.opened
    }
}

/// The default cache folder: `$PALPUS_CACHE_DIR`, else `$XDG_CACHE_HOME/palpus/models`, else
/// `~/.cache/palpus/models`, else `.palpus-cache` here.
pub fn default_cache_dir() -> PathBuf {
    if let Some(dir) = std::env::var_os("PALPUS_CACHE_DIR") {
        return PathBuf::from(dir);
    }
    if let Some(dir) = std::env::var_os("XDG_CACHE_HOME") {
        return PathBuf::from(dir).join("palpus").join("models");
    }
    if let Some(home) = std::env::var_os("HOME") {
        return PathBuf::from(home).join(".cache").join("palpus").join("models");
    }
    PathBuf::from(".palpus-cache")
}

/// `needle`/`needle_phases`/`hard`/`soft` to the model kind (the scene validated the name).
pub fn kind_of(name: &str) -> ModelKind {
    match name {
        "hard" => ModelKind::HardFriction,
        "soft" => ModelKind::SoftFriction,
        "needle_phases" => ModelKind::NeedlePhases,
        _ => ModelKind::NeedlePuncture,
    }
}

/// Resolves the models `scene`'s drawn objects reference, reading files through `sources`.
/// `fitting` is told when an identification starts (name, capture) and ends.
pub fn resolve(
    scene: &Scene,
    cache_dir: &Path,
    sources: &mut Sources<'_>,
    fitting: &mut dyn FnMut(FitEvent<'_>),
) -> Result<Vec<ResolvedModel>, ModelError> {
    let mut out = Vec::new();
    for (name, role, _) in scene.referenced_models() {
        let Some(source) = scene.models.get(&name) else {
            continue; // validation guarantees it exists
        };
        let (model, origin, budget) = resolve_one(scene, &name, source, cache_dir, sources, fitting)?;
        out.push(ResolvedModel {
            name,
            role,
            model,
            origin,
            budget,
        });
    }
    Ok(out)
}

/// Progress of an identification.
#[derive(Debug, Clone, Copy)]
pub enum FitEvent<'a> {
    /// Fitting `model` from `capture` started.
    Started {
        /// The scene's name for the model.
        model: &'a str,
        /// The training capture.
        capture: &'a Path,
    },
    /// It ended after `elapsed`.
    Finished {
        /// The scene's name for the model.
        model: &'a str,
        /// Fitting time.
        elapsed: Duration,
    },
}

fn resolve_one(
    scene: &Scene,
    name: &str,
    source: &ModelSource,
    cache_dir: &Path,
    sources: &mut Sources<'_>,
    fitting: &mut dyn FnMut(FitEvent<'_>),
) -> Result<(ModelFile, Origin, Option<BudgetChoice>), ModelError> {
    let kind = kind_of(&source.kind);
    if let Some(file) = &source.file {
        let path = scene.resolve(file);
        let bytes = sources.read_model_source(name, &path)?;
        let model = ModelFile::from_slice(&bytes, &path).map_err(|e| ModelError::File {
            model: name.into(),
            source: Box::new(e),
        })?;
        check_kind(name, &path, kind, &model)?;
        check_renderable(name, &path, &model, &scene.device_specs())?;
        return Ok((model, Origin::File(path), None));
    }
    let Some(capture) = &source.capture else {
        return Err(ModelError::Read {
            model: name.into(),
            path: PathBuf::new(),
            source: std::io::Error::other("neither `file` nor `capture` given"),
        });
    };
    let path = scene.resolve(capture);
    let bytes = sources.read_model_source(name, &path)?;
    let mut knobs = FitKnobs::default();
    let (options, budget) = match &source.budget {
        None => (
            IdentifyOptions {
                kind,
                c: source.c,
                epsilon: source.epsilon,
                gamma: source.gamma,
                max_samples: source.max_samples(),
                max_fit_samples: identify::DEFAULT_MAX_FIT_SAMPLES,
                keep_outliers: false,
            },
            None,
        ),
        Some(budget) => {
            let choice = choose_from_front(scene, name, kind, &path, &bytes, budget, sources)?;
            let options = IdentifyOptions {
                kind,
                c: Some(choice.c),
                epsilon: Some(choice.epsilon),
                gamma: choice.gamma,
                max_samples: choice.n,
                max_fit_samples: identify::DEFAULT_MAX_FIT_SAMPLES,
                keep_outliers: false,
            };
            knobs = FitKnobs {
                tolerance: choice.tol,
                max_sv: choice.max_sv,
            };
            (options, Some(choice))
        }
    };
    let cached = cache_dir.join(format!(
        "{}-{}.json",
        kind.short_name(),
        cache_key(&bytes, &options, knobs)
    ));
    if cached.is_file()
        && let Ok(model) = ModelFile::load(&cached)
        && model.kind == kind
    {
        check_renderable(name, &cached, &model, &scene.device_specs())?;
        return Ok((model, Origin::Cached(cached), budget));
    }
    let capture_kind = if matches!(kind, ModelKind::NeedlePuncture | ModelKind::NeedlePhases) {
        CaptureKind::Insertion
    } else {
        CaptureKind::Rubbing
    };
    let train =
        Capture::read_from(BufReader::new(bytes.as_slice()), &path, Some(capture_kind)).map_err(|e| {
            ModelError::Capture {
                model: name.into(),
                source: Box::new(e),
            }
        })?;
    fitting(FitEvent::Started {
        model: name,
        capture: &path,
    });
    let started = Instant::now();
    let limits = FitLimits {
        tolerance: knobs.tolerance,
        max_sv: knobs.max_sv,
        ..FitLimits::default()
    };
    let identified = identify_with(&train, None, &options, &limits).map_err(|e| ModelError::Identify {
        model: name.into(),
        path: path.clone(),
        source: Box::new(e),
    })?;
    let elapsed = started.elapsed();
    fitting(FitEvent::Finished { model: name, elapsed });
    check_renderable(name, &path, &identified.model, &scene.device_specs())?;
    std::fs::create_dir_all(cache_dir).map_err(|e| ModelError::Read {
        model: name.into(),
        path: cache_dir.to_owned(),
        source: e,
    })?;
    identified.model.save(&cached).map_err(|e| ModelError::Cache {
        model: name.into(),
        source: Box::new(e),
    })?;
    Ok((
        identified.model,
        Origin::Identified {
            cached,
            seconds: elapsed.as_secs_f64(),
        },
        budget,
    ))
}

/// The point of `budget.front` (a trade table measured on the scene's capture, whose bytes
/// are `capture_bytes`) that `budget` picks for the model `name` of `kind`.
fn choose_from_front(
    scene: &Scene,
    name: &str,
    kind: ModelKind,
    capture_path: &Path,
    capture_bytes: &[u8],
    budget: &ModelBudget,
    sources: &mut Sources<'_>,
) -> Result<BudgetChoice, ModelError> {
    let front = scene.resolve(&budget.front);
    let refuse = |reason: String| ModelError::Budget {
        model: name.into(),
        path: front.clone(),
        reason,
    };
    let bytes = sources.read_model_source(name, &front)?;
    let table = TradeTable::parse(&bytes, &front).map_err(|e| refuse(e.reason_with_place()))?;
    if table.model != kind {
        return Err(refuse(format!(
            "it measured a {} model, the scene's is {kind}",
            table.model
        )));
    }
    if table.capture_sha256 != sha256_hex(capture_bytes) {
        return Err(refuse(format!(
            "it was measured on another capture than {} (their SHA-256 differ): measure it again with `palpus bench trade {} --model {kind} --out DIR`",
            capture_path.display(),
            capture_path.display()
        )));
    }
    let limits = Budget {
        max_predict_ns: budget.max_predict_ns,
        max_aise: budget.max_aise,
    };
    let choice = table.choose(&limits).map_err(refuse)?;
    let row = choice.row;
    Ok(BudgetChoice {
        front: front.clone(),
        max_predict_ns: limits.max_predict_ns,
        max_aise: limits.max_aise,
        n: row.n,
        c: row.point.c,
        epsilon: row.point.epsilon,
        gamma: row.point.gamma,
        tol: row.tol,
        max_sv: row.max_sv,
        predict_ns: row.time_ns(),
        aise: row.aise(),
        within: choice.within,
        measured: choice.measured,
    })
}

fn check_kind(name: &str, path: &Path, expected: ModelKind, model: &ModelFile) -> Result<(), ModelError> {
    if model.kind == expected {
        Ok(())
    } else {
        Err(ModelError::WrongKind {
            model: name.into(),
            path: path.to_owned(),
            expected,
            found: model.kind,
        })
    }
}

/// Refuses a model that `device` cannot render: one whose force is not proved within the
/// device's limit over every input its law can see (and, for a needle, physical in sign and
/// threshold; [`identify::ModelFile::certify`]), or one no force law builds from. `path` is the
/// file (or capture) named in errors.
pub fn check_renderable(
    name: &str,
    path: &Path,
    model: &ModelFile,
    device: &haptics::DeviceSpecs,
) -> Result<(), ModelError> {
    let envelope = identify::DeviceEnvelope {
        max_force_n: device.max_force_n,
        stroke_m: 2.0 * device.workspace_radius_m,
    };
    model.certify(&envelope).map_err(|source| ModelError::Unsafe {
        model: name.into(),
        path: path.to_owned(),
        source: Box::new(source),
    })?;
    // Build the fast path the force law will use, so that what it refuses is refused here,
    // with the file named, rather than when the session starts.
    let law = |source| ModelError::Law {
        model: name.into(),
        path: path.to_owned(),
        source: Box::new(source),
    };
    match model.kind {
        ModelKind::NeedlePuncture => haptics::needle_model(model).map(drop),
        ModelKind::NeedlePhases => {
            haptics::PhasedNeedleLaw::from_file(model, haptics::NeedleLawConfig::default()).map(drop)
        }
        ModelKind::HardFriction => haptics::hard_friction_model(model).map(drop),
        ModelKind::SoftFriction => haptics::soft_friction_models(model).map(drop),
    }
    .map_err(law)
}

/// The solver settings a budget's chosen point was measured with, beside its hyperparameters.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FitKnobs {
    /// Solver tolerance (`None`: the library's default).
    pub tolerance: Option<f64>,
    /// Support-vector budget (`None`: none).
    pub max_sv: Option<usize>,
}

/// SHA-256 (first 16 hex digits) of what determines an identified model.
pub fn cache_key(capture_bytes: &[u8], options: &IdentifyOptions, knobs: FitKnobs) -> String {
    let mut h = Sha256::new();
    h.update(CACHE_VERSION.as_bytes());
    h.update(options.kind.short_name().as_bytes());
    h.update((capture_bytes.len() as u64).to_le_bytes());
    h.update(capture_bytes);
    // `{:?}` of an f64 round-trips, so two different values never share a key.
    let hyper = format!(
        "c={:?};epsilon={:?};gamma={:?};max_samples={};max_fit_samples={}",
        options.c, options.epsilon, options.gamma, options.max_samples, options.max_fit_samples
    );
    h.update(hyper.as_bytes());
    // Only when set, so that the keys of models identified without them stay as they were.
    if let Some(t) = knobs.tolerance {
        h.update(format!(";tol={t:?}").as_bytes());
    }
    if let Some(k) = knobs.max_sv {
        h.update(format!(";max_sv={k}").as_bytes());
    }
    h.finalize().iter().take(8).map(|b| format!("{b:02x}")).collect()
}

/// [`resolve`] from the files on disk, with a spinner on the terminal while a model is fitted.
pub fn resolve_with_progress(scene: &Scene, cache_dir: &Path) -> anyhow::Result<Vec<ResolvedModel>> {
    let mut sources = Sources::default();
    let mut bar: Option<ProgressBar> = None;
    let resolved = resolve(scene, cache_dir, &mut sources, &mut |event| match event {
        FitEvent::Started { model, capture } => {
            let b = ProgressBar::new_spinner().with_style(
                ProgressStyle::with_template("{spinner} identifying {msg} {elapsed}")
                    .unwrap_or_else(|_| ProgressStyle::default_spinner()),
            );
            b.set_message(format!("`{model}` from {}", capture.display()));
            b.enable_steady_tick(Duration::from_millis(100));
            bar = Some(b);
        }
        FitEvent::Finished { .. } => {
            if let Some(b) = bar.take() {
                b.finish_and_clear();
            }
        }
    })
    .with_context(|| format!("resolving the models of {}", scene.path.display()))?;
    Ok(resolved)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn root() -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
    }

    /// The smooth-needle scene plus friction models no object references, one of them
    /// pointing at a capture that does not exist.
    fn needle_only_scene() -> Scene {
        let text = std::fs::read_to_string(root().join("scenes/needle_liver_smooth.toml")).unwrap().replace(
            "[task]",
            "[models.hard]\nkind = \"hard\"\ncapture = \"../assets/captures/li_bi/hard_contact_train.csv\"\n\n\
             [models.soft]\nkind = \"soft\"\ncapture = \"../missing/soft.csv\"\n\n[task]",
        );
        Scene::parse(&text, &root().join("scenes/needle_only.toml")).unwrap()
    }

    #[test]
    fn a_needle_only_scene_never_opens_the_friction_captures() {
        let scene = needle_only_scene();
        let cache = tempfile::tempdir().unwrap();
        let mut sources = Sources::default();
        let mut fits = 0;
        let models = resolve(&scene, cache.path(), &mut sources, &mut |e| {
            fits += usize::from(matches!(e, FitEvent::Started { .. }));
        })
        .unwrap();
        assert_eq!(models.len(), 1);
        assert_eq!(models[0].model.kind, ModelKind::NeedlePuncture);
        assert_eq!(fits, 1);
        // The needle's capture and the trade its budget picks from, nothing else.
        let opened: Vec<_> = sources.opened().iter().collect();
        assert_eq!(
            opened,
            [
                &scene.resolve(Path::new("../assets/captures/li_bi/needle_train.csv")),
                &scene.resolve(Path::new("../assets/models/needle_liver_trade/trade.csv"))
            ]
        );
        assert!(
            !sources
                .opened()
                .iter()
                .any(|p| p.to_string_lossy().contains("contact"))
        );
    }

    #[test]
    fn the_cache_serves_the_same_bytes_and_hyperparameters_only() {
        // Hyperparameters given, not picked by a budget.
        let mut scene = needle_only_scene();
        if let Some(m) = scene.models.get_mut("needle_liver") {
            m.budget = None;
        }
        let cache = tempfile::tempdir().unwrap();
        let capture = scene.resolve(Path::new("../assets/captures/li_bi/needle_train.csv"));
        let bytes = std::fs::read(&capture).unwrap();
        let first = resolve(&scene, cache.path(), &mut Sources::default(), &mut |_| {}).unwrap();
        assert!(matches!(first[0].origin, Origin::Identified { .. }));
        let again = resolve(&scene, cache.path(), &mut Sources::default(), &mut |_| {}).unwrap();
        assert!(matches!(again[0].origin, Origin::Cached(_)));
        assert_eq!(again[0].model, first[0].model);

        // Other hyperparameters: identified anew.
        let mut other = scene.clone();
        if let Some(m) = other.models.get_mut("needle_liver") {
            m.gamma = Some(10.0);
        }
        let changed = resolve(&other, cache.path(), &mut Sources::default(), &mut |_| {}).unwrap();
        assert!(matches!(changed[0].origin, Origin::Identified { .. }));
        assert_ne!(changed[0].model.body, first[0].model.body);

        // Other capture bytes under the same path: identified anew (one row's force changed).
        let text = String::from_utf8(bytes.clone()).unwrap();
        let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
        let last = lines.len() - 1;
        let mut fields: Vec<String> = lines[last].split(',').map(str::to_owned).collect();
        let n = fields.len() - 1;
        let f: f64 = fields[n].parse().unwrap();
        fields[n] = format!("{}", f + 0.001);
        lines[last] = fields.join(",");
        let edited = lines.join("\n") + "\n";
        let mut sources = Sources::new(|p: &Path| {
            if p == capture {
                Ok(edited.clone().into_bytes())
            } else {
                std::fs::read(p)
            }
        });
        let reread = resolve(&scene, cache.path(), &mut sources, &mut |_| {}).unwrap();
        assert!(matches!(reread[0].origin, Origin::Identified { .. }));
        let key = |b: &[u8]| {
            cache_key(
                b,
                &IdentifyOptions::new(ModelKind::NeedlePuncture),
                FitKnobs::default(),
            )
        };
        assert_ne!(key(&bytes), key(edited.as_bytes()));
    }

    #[test]
    fn a_model_file_of_the_wrong_kind_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let hard = Capture::read_file(
            root().join("assets/captures/li_bi/hard_contact_train.csv"),
            CaptureKind::Rubbing,
        )
        .unwrap();
        let model = identify::identify(&hard, None, &IdentifyOptions::new(ModelKind::HardFriction))
            .unwrap()
            .model;
        let path = dir.path().join("hard.json");
        model.save(&path).unwrap();
        let mut scene = needle_only_scene();
        if let Some(m) = scene.models.get_mut("needle_liver") {
            m.capture = None;
            m.file = Some(path.clone());
        }
        let e = resolve(&scene, dir.path(), &mut Sources::default(), &mut |_| {}).unwrap_err();
        assert!(matches!(e, ModelError::WrongKind { .. }), "{e}");
        assert!(
            e.to_string().contains("hard.json") && e.to_string().contains("needle"),
            "{e}"
        );
    }
}

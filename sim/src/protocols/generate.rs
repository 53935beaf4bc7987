//! `palpus gen`: writes a reproducible capture set to a folder.

use std::fmt;
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use capture::{Capture, CaptureError, write_atomically};

use super::split::Split;
use super::{li_bi, multistream, nakano, sinapov};
use crate::SimError;
use crate::world::scratch::{Behaviour, household_surfaces};
use crate::world::surface::{SurfacePatch, nakano_surfaces};

/// The groups of captures `generate` can write.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum CaptureSet {
    /// Li & Bi: hard contact, soft contact, needle insertion; a train and a test capture each.
    LiBi,
    /// Nakano: 7 surfaces × 3 rubbing runs.
    Nakano,
    /// Sinapov: 20 surfaces + air × 5 behaviours × 10 trials.
    Sinapov,
    /// A sliding study logged as one CSV per stream on its own clock (not captures: input for
    /// `palpus import`); only when asked for, never in [`CaptureSet::ALL`].
    Multistream,
}

impl CaptureSet {
    /// Every set, in generation order.
    pub const ALL: [CaptureSet; 3] = [Self::LiBi, Self::Nakano, Self::Sinapov];

    /// Name on the command line and folder name.
    pub fn name(self) -> &'static str {
        match self {
            Self::LiBi => "li_bi",
            Self::Nakano => "nakano",
            Self::Sinapov => "sinapov",
            Self::Multistream => multistream::FOLDER,
        }
    }
}

impl fmt::Display for CaptureSet {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for CaptureSet {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .into_iter()
            .chain([Self::Multistream])
            .find(|set| set.name() == s.replace('-', "_"))
            .ok_or_else(|| {
                format!("unknown capture set `{s}` (expected one of: li_bi, nakano, sinapov, multistream)")
            })
    }
}

/// One written capture.
#[derive(Debug, Clone, PartialEq)]
pub struct Generated {
    /// Path relative to the output folder.
    pub path: PathBuf,
    /// Protocol name, as in the capture's metadata.
    pub protocol: &'static str,
    /// What the capture is of: surface, tissue or contact.
    pub label: String,
    /// `train`, `test`, or the behaviour for scratches.
    pub role: String,
    /// Number of samples.
    pub rows: usize,
    /// Size on disk.
    pub bytes: u64,
}

/// What `generate` wrote.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct GenSummary {
    /// Every capture, in the order written.
    pub files: Vec<Generated>,
}

impl GenSummary {
    /// Samples over all captures.
    pub fn total_rows(&self) -> usize {
        self.files.iter().map(|g| g.rows).sum()
    }

    /// Bytes over all captures (the manifest excluded).
    pub fn total_bytes(&self) -> u64 {
        self.files.iter().map(|g| g.bytes).sum()
    }
}

/// File name of the manifest written next to the captures.
pub const MANIFEST: &str = "MANIFEST.csv";

/// Writes the chosen capture sets under `out`, one sub-folder per set, plus a manifest listing
/// every capture (`path,protocol,label,role,rows`). Each capture is written atomically; a rerun
/// with the same seed rewrites identical bytes. `progress` is called after each capture.
pub fn generate(
    out: &Path,
    seed: u64,
    sets: &[CaptureSet],
    progress: &mut dyn FnMut(&Generated),
) -> Result<GenSummary, SimError> {
    let mut writer = Writer::new(out, progress);
    let mut sets = sets.to_vec();
    sets.sort();
    sets.dedup();
    let logs = sets.contains(&CaptureSet::Multistream);
    for set in sets {
        match set {
            CaptureSet::LiBi => {
                type Simulate = fn(u64, Split) -> Result<Capture, CaptureError>;
                let experiments: [(&str, Simulate, &'static str, &str); 3] = [
                    (
                        "hard_contact",
                        li_bi::hard_contact,
                        "li_bi_hard_contact",
                        "aluminium_plate",
                    ),
                    (
                        "soft_contact",
                        li_bi::soft_contact,
                        "li_bi_soft_contact",
                        "sponge",
                    ),
                    ("needle", li_bi::needle_insertion, "li_bi_needle", "bovine_liver"),
                ];
                for split in [Split::Train, Split::Test] {
                    let s = split.as_str();
                    for (file, simulate, protocol, object) in experiments {
                        writer.capture(
                            format!("li_bi/{file}_{s}.csv").into(),
                            simulate(seed, split),
                            protocol,
                            object.into(),
                            s.into(),
                        )?;
                    }
                }
            }
            CaptureSet::Nakano => {
                for surface in nakano_surfaces() {
                    let patch = SurfacePatch::new(&surface);
                    for run in 0..nakano::RUNS {
                        let role = if run == 0 { "train" } else { "test" };
                        writer.capture(
                            format!("nakano/{}", nakano::run_file_name(&surface, run)).into(),
                            nakano::rubbing_run(&patch, run, seed),
                            "nakano_rubbing",
                            surface.name.into(),
                            role.into(),
                        )?;
                    }
                }
            }
            CaptureSet::Sinapov => {
                for surface in household_surfaces() {
                    for behaviour in Behaviour::ALL {
                        for trial in 0..sinapov::TRIALS {
                            writer.capture(
                                format!("sinapov/{}/{}_t{trial:02}.csv", surface.name, behaviour.name())
                                    .into(),
                                sinapov::scratch_capture(&surface, behaviour, trial, seed),
                                "sinapov_scratch",
                                surface.name.into(),
                                behaviour.name().into(),
                            )?;
                        }
                    }
                }
            }
            // Logs, not captures: written below, once `write` is done with the summary.
            CaptureSet::Multistream => {}
        }
    }
    if logs {
        writer.logs(seed, multistream::SlidingStudy::default())?;
    }
    write_manifest(out, &writer.summary)?;
    Ok(writer.summary)
}

/// One set written on its own, with settings of its own, into the folder the full set uses,
/// without touching the other sets or the manifest (`palpus gen --needle-rate-hz`,
/// `--rub-speed-mps`, `--two-patch`, `--slide-speed-mps`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Variant {
    /// Li & Bi's needle training and held-out captures with this protocol (`li_bi/`).
    Needle(li_bi::NeedleProtocol),
    /// Nakano's rubbing runs at this speed, m/s (`nakano/`).
    Rubbing {
        /// The tip's speed, m/s.
        speed_mps: f64,
    },
    /// Each Nakano surface rubbed onto the next halfway through the stroke, runs 1 and 2, at
    /// this speed, m/s (`nakano_two_patch/`).
    TwoPatch {
        /// The tip's speed, m/s.
        speed_mps: f64,
    },
    /// The multi-stream sliding study of this shape, speed and slide time (`multistream/`).
    Sliding(multistream::SlidingStudy),
}

/// Writes `variant` under `out` (see [`Variant`]); `progress` is called after each file.
pub fn generate_variant(
    out: &Path,
    seed: u64,
    variant: Variant,
    progress: &mut dyn FnMut(&Generated),
) -> Result<GenSummary, SimError> {
    let mut writer = Writer::new(out, progress);
    match variant {
        Variant::Needle(protocol) => {
            for split in [Split::Train, Split::Test] {
                let s = split.as_str();
                writer.capture(
                    format!("li_bi/needle_{s}.csv").into(),
                    li_bi::needle_insertion_with(seed, split, protocol),
                    "li_bi_needle",
                    protocol.tissue.name().into(),
                    s.into(),
                )?;
            }
        }
        Variant::Rubbing { speed_mps } => {
            for surface in nakano_surfaces() {
                let patch = SurfacePatch::new(&surface);
                for run in 0..nakano::RUNS {
                    writer.capture(
                        format!("nakano/{}", nakano::run_file_name(&surface, run)).into(),
                        nakano::rubbing_run_at(&patch, run, seed, speed_mps),
                        "nakano_rubbing",
                        surface.name.into(),
                        if run == 0 { "train" } else { "test" }.into(),
                    )?;
                }
            }
        }
        Variant::TwoPatch { speed_mps } => {
            let patches: Vec<SurfacePatch> = nakano_surfaces().iter().map(SurfacePatch::new).collect();
            for (i, first) in patches.iter().enumerate() {
                let second = &patches[(i + 1) % patches.len()];
                // Run 0 is the training run of the single-surface set; these are test strokes.
                for run in 1..nakano::RUNS {
                    writer.capture(
                        format!(
                            "nakano_two_patch/{}",
                            nakano::two_patch_file_name(first.surface(), second.surface(), run)
                        )
                        .into(),
                        nakano::two_patch_run(first, second, run, seed, speed_mps),
                        "nakano_two_patch",
                        format!("{}+{}", first.surface().name, second.surface().name),
                        "test".into(),
                    )?;
                }
            }
        }
        Variant::Sliding(study) => {
            study.check()?;
            writer.logs(seed, study)?;
        }
    }
    Ok(writer.summary)
}

/// Writes files under `out` and keeps the summary of what it wrote.
struct Writer<'a> {
    out: &'a Path,
    summary: GenSummary,
    progress: &'a mut dyn FnMut(&Generated),
}

impl<'a> Writer<'a> {
    fn new(out: &'a Path, progress: &'a mut dyn FnMut(&Generated)) -> Self {
        Self {
            out,
            summary: GenSummary::default(),
            progress,
        }
    }

    /// Writes `capture` to `out/relative` atomically.
    fn capture(
        &mut self,
        relative: PathBuf,
        capture: Result<Capture, CaptureError>,
        protocol: &'static str,
        label: String,
        role: String,
    ) -> Result<(), SimError> {
        let capture = capture.map_err(|source| SimError::GeneratedCapture {
            path: relative.clone(),
            source: Box::new(source),
        })?;
        let path = self.out.join(&relative);
        if let Some(parent) = path.parent() {
            fs::create_dir_all(parent).map_err(|source| SimError::Io {
                action: "write",
                path: parent.to_owned(),
                source,
            })?;
        }
        capture
            .write_file(&path)
            .map_err(|source| SimError::GeneratedCapture {
                path: relative.clone(),
                source: Box::new(source),
            })?;
        let bytes = fs::metadata(&path)
            .map_err(|source| SimError::Io {
                action: "write",
                path: path.clone(),
                source,
            })?
            .len();
        self.record(Generated {
            path: relative,
            protocol,
            label,
            role,
            rows: capture.len(),
            bytes,
        });
        Ok(())
    }

    /// Writes the multi-stream sliding study's logs.
    fn logs(&mut self, seed: u64, study: multistream::SlidingStudy) -> Result<(), SimError> {
        let out = self.out;
        multistream::write_logs(out, seed, study, &mut |file| {
            self.record(Generated {
                path: file.path,
                protocol: multistream::PROTOCOL,
                label: file.surface.into(),
                role: file.stream.into(),
                rows: file.rows,
                bytes: file.bytes,
            });
        })
    }

    fn record(&mut self, generated: Generated) {
        (self.progress)(&generated);
        self.summary.files.push(generated);
    }
}

fn write_manifest(out: &Path, summary: &GenSummary) -> Result<(), SimError> {
    let path = out.join(MANIFEST);
    write_atomically(&path, |w| {
        writeln!(w, "path,protocol,label,role,rows")?;
        for g in &summary.files {
            writeln!(
                w,
                "{},{},{},{},{}",
                g.path.display(),
                g.protocol,
                g.label,
                g.role,
                g.rows
            )?;
        }
        Ok(())
    })
    .map_err(|source: std::io::Error| SimError::Io {
        action: "write",
        path,
        source,
    })
}

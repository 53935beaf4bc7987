//! `palpus recognize categorize`: surface categories after Sinapov et al. from a recognizer's
//! confusions on labelled captures — a similarity matrix, a hierarchy by recursive normalized
//! cuts, and a 2-D map of the surfaces.

use std::path::{Path, PathBuf};

use anyhow::Context;
use recognize::SettingError;
use recognize::{
    CategoryTree, FeatureNeeds, LabelledCapture, RecognizeError, RecognizerFile, StopRule, classical_mds,
    distances_from_similarity, isomap, recursive_ncut, similarity_from_confusion, surface_confusion,
};

use super::chosen_training::{ChosenTraining, read_and_choose};
use super::kept_reading::keeping_each;
use super::train_args::{Method, TrainOptions};

/// Group surfaces into a hierarchy of categories by how often the recognizer confuses them.
///
/// Evaluates the recognizer MODEL.json on the captures (or, with --leave-surface-out, trains
/// one recognizer per surface on all the others and classifies the one left out, Sinapov's
/// surface-based cross-validation), turns the confusion matrix into a similarity
/// (symmetrised row rates, 1 on the diagonal), splits the surfaces recursively by Shi & Malik's
/// normalized cut, and writes `similarity.csv`, `categories.json` and `mds.png` (ISOMAP of
/// `1 − similarity`, or classical MDS when the neighbour graph is disconnected) to `--out`.
#[derive(Debug, clap::Args)]
pub(crate) struct CategorizeArgs {
    /// The recognizer file (`palpus recognize train`) followed by labelled captures to
    /// evaluate it on (captures it was not trained on, so it errs); with --leave-surface-out,
    /// the captures only.
    #[arg(required = true, value_name = "MODEL.json] [CAPTURES")]
    inputs: Vec<PathBuf>,
    /// Sinapov's similarity: for each surface, train on every other surface (with --method
    /// and the other training options of `recognize train`, what they leave unnamed chosen
    /// first on all the captures as `train` chooses it) and classify each scratch of the one
    /// left out, so every decision names the known surface it resembles most.
    #[arg(long, requires = "method")]
    leave_surface_out: bool,
    /// With --leave-surface-out: which recognizer to train (the training options below apply
    /// only then).
    #[arg(long, value_enum, requires = "leave_surface_out")]
    method: Option<Method>,
    #[command(flatten)]
    training: TrainOptions,
    /// Folder for similarity.csv, categories.json and mds.png (created if missing).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Keep a category whole when its best cut's Ncut value exceeds this (0–2).
    #[arg(long, default_value_t = 0.5)]
    max_ncut: f64,
    /// Do not split categories with fewer surfaces than this (Sinapov et al. used 5; with a
    /// recognizer that seldom errs, most cuts are cheap and 2 splits down to single surfaces).
    #[arg(long, default_value_t = 5)]
    min_size: usize,
    /// ISOMAP neighbours; 0 for classical MDS.
    #[arg(long, default_value_t = 4)]
    isomap_k: usize,
}

pub(crate) fn run(args: &CategorizeArgs) -> anyhow::Result<()> {
    // Each capture is held only as the features training and deciding read.
    let read = |paths: &[PathBuf],
                needs: &mut dyn FnMut(&LabelledCapture) -> anyhow::Result<FeatureNeeds>| {
        keeping_each(
            paths,
            |p| {
                let c =
                    LabelledCapture::read(p).with_context(|| format!("reading capture {}", p.display()))?;
                Ok(vec![c])
            },
            needs,
        )
    };
    let (method, confusion) = match args.method {
        Some(method) => {
            // One recognizer per surface, each with the given seed; what the options leave
            // unnamed is chosen on all the captures, by recording, before any is left out.
            let ChosenTraining {
                settings, captures, ..
            } = read_and_choose(
                &args.training,
                method,
                &|needs| read(&args.inputs, needs),
                // Confusions are counted window by window: no posterior, no weight to fit.
                &|settings| recognize::TrainSettings {
                    fit_posterior_weight: false,
                    ..settings
                },
                &FeatureNeeds::training_and_decisions,
            )?;
            let confusion = surface_confusion(&captures, |train, _| {
                recognize::train(train, &settings).map_err(Box::new)
            })?;
            (
                format!("{} trained leaving each surface out", settings.method.name()),
                confusion,
            )
        }
        None => {
            let [model, captures @ ..] = args.inputs.as_slice() else {
                anyhow::bail!("give MODEL.json and captures");
            };
            if captures.is_empty() {
                anyhow::bail!("give captures after {} to evaluate it on", model.display());
            }
            let model = RecognizerFile::load(model)?;
            let captures = read(captures, &mut |_| Ok(FeatureNeeds::evaluation(&model, &[])?))?;
            let e = model.evaluate(&captures, None)?;
            (e.method.to_owned(), e.confusion)
        }
    };
    let names = confusion.classes().to_vec();
    let similarity = similarity_from_confusion(confusion.counts())?;
    let tree = recursive_ncut(
        &similarity,
        StopRule {
            max_ncut: args.max_ncut,
            min_size: args.min_size,
        },
    )?;
    let distances = distances_from_similarity(&similarity)?;
    // ISOMAP needs a connected neighbour graph; a recognizer that never confuses some groups
    // leaves them at equal distance 1, where classical MDS still gives a faithful picture.
    let k = args.isomap_k.min(names.len().saturating_sub(1));
    let (embedding, points) = match k {
        0 => ("mds".to_owned(), classical_mds::<2>(&distances)?),
        k => match isomap::<2>(&distances, k) {
            Ok(p) => (format!("isomap k={k}"), p),
            Err(RecognizeError::Setting(SettingError::Disconnected { .. })) => {
                ("mds".to_owned(), classical_mds::<2>(&distances)?)
            }
            Err(other) => return Err(other.into()),
        },
    };
    std::fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    write_similarity(&args.out.join("similarity.csv"), &names, &similarity)?;
    let json = serde_json::json!({
        "method": method,
        "decisions": confusion.total(),
        "accuracy": confusion.accuracy(),
        "classes": names,
        "similarity": similarity,
        "stop": { "max_ncut": args.max_ncut, "min_size": args.min_size },
        "tree": tree_json(&tree, &names),
        "embedding": {
            "method": embedding,
            "points": names.iter().zip(&points).map(|(n, p)| serde_json::json!({"class": n, "x": p[0], "y": p[1]})).collect::<Vec<_>>(),
        },
    });
    let json_path = args.out.join("categories.json");
    capture::write_atomically(&json_path, |w| {
        serde_json::to_writer_pretty(&mut *w, &json).map_err(std::io::Error::other)?;
        std::io::Write::write_all(w, b"\n")
    })
    .with_context(|| format!("writing {}", json_path.display()))?;
    crate::plots::write_scatter(&args.out.join("mds.png"), &names, &points, &tree, &embedding)?;
    println!(
        "{method}: {} decisions, accuracy {}",
        confusion.total(),
        confusion
            .accuracy()
            .map_or_else(|| "-".to_owned(), |a| format!("{:.1} %", 100.0 * a))
    );
    println!("categories (recursive normalized cut):");
    print!("{}", tree.to_text(&names));
    println!(
        "{} leaf categories; wrote similarity.csv, categories.json, mds.png ({embedding}) to {}",
        tree.leaves().len(),
        args.out.display()
    );
    Ok(())
}

fn tree_json(tree: &CategoryTree, names: &[String]) -> serde_json::Value {
    serde_json::json!({
        "members": tree.members.iter().map(|&i| names.get(i).cloned().unwrap_or_default()).collect::<Vec<_>>(),
        "ncut": tree.ncut,
        "children": tree.children.iter().map(|c| tree_json(c, names)).collect::<Vec<_>>(),
    })
}

/// A header row of class names, then one row per class: its name and its similarities.
fn write_similarity(path: &Path, names: &[String], s: &[Vec<f64>]) -> anyhow::Result<()> {
    let mut text = String::from("class");
    for n in names {
        text.push(',');
        text.push_str(n);
    }
    text.push('\n');
    for (n, row) in names.iter().zip(s) {
        text.push_str(n);
        for v in row {
            text.push_str(&format!(",{v}"));
        }
        text.push('\n');
    }
    capture::write_atomically(path, |w| std::io::Write::write_all(w, text.as_bytes()))
        .with_context(|| format!("writing {}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    use recognize::{CellScale, KnnParams};
    use sim::sinapov::scratch_capture;
    use sim::{Behaviour, household_surfaces};

    #[test]
    fn categorizes_knn_confusions_on_generated_scratches() {
        let dir = tempfile::tempdir().unwrap();
        let behaviour = Behaviour::ALL[0];
        let (mut train, mut test) = (Vec::new(), Vec::new());
        for surface in household_surfaces().iter().take(5) {
            for trial in 0..8 {
                let capture = scratch_capture(surface, behaviour, trial, 1).unwrap();
                let path = dir.path().join(format!("{}_{trial}.csv", surface.name));
                capture.write_file(&path).unwrap();
                if trial < 4 { &mut train } else { &mut test }.push(path);
            }
        }
        let labelled: Vec<LabelledCapture> =
            train.iter().map(|p| LabelledCapture::read(p).unwrap()).collect();
        let model = RecognizerFile::train_knn(&labelled, KnnParams::default().k(3), CellScale::Mean).unwrap();
        let model_path = dir.path().join("knn.json");
        model.save(&model_path).unwrap();
        let out = dir.path().join("cat");
        #[derive(clap::Parser)]
        struct Command {
            #[command(flatten)]
            args: CategorizeArgs,
        }
        let mut argv: Vec<std::ffi::OsString> = vec!["categorize".into(), model_path.into()];
        argv.extend(test.into_iter().map(Into::into));
        argv.extend(["--out".into(), out.clone().into()]);
        argv.extend(["--min-size", "2", "--isomap-k", "3"].map(Into::into));
        let command = <Command as clap::Parser>::try_parse_from(argv).unwrap();
        run(&command.args).unwrap();
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("categories.json")).unwrap()).unwrap();
        let classes = json["classes"].as_array().unwrap();
        assert_eq!(classes.len(), 5);
        let mut top = json["tree"]["members"].as_array().unwrap().clone();
        top.sort_by_key(|v| v.to_string());
        let mut sorted = classes.clone();
        sorted.sort_by_key(|v| v.to_string());
        assert_eq!(top, sorted, "the root holds every class");
        assert_eq!(json["embedding"]["points"].as_array().unwrap().len(), 5);
        let csv = std::fs::read_to_string(out.join("similarity.csv")).unwrap();
        assert_eq!(csv.lines().count(), 6);
        let png = std::fs::read(out.join("mds.png")).unwrap();
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    }
}

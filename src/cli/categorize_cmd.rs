//! `palpus recognize categorize`: surface categories after Sinapov et al. from a recognizer's
//! confusions on labelled captures — a similarity matrix, a hierarchy by recursive normalized
//! cuts, and a 2-D map of the surfaces.

use std::path::{Path, PathBuf};

use anyhow::Context;
use plotters::prelude::*;
use plotters::style::FontStyle;
use recognize::category::{
    CategoryError, CategoryTree, StopRule, classical_mds, distances_from_similarity, isomap, recursive_ncut,
    similarity_from_confusion,
};
use recognize::model::{LabelledCapture, RecognizerFile};
use recognize::protocol::surface_confusion;

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
    /// and the other training options of `recognize train`) and classify each scratch of the
    /// one left out, so every decision names the known surface it resembles most.
    #[arg(long, requires = "method")]
    leave_surface_out: bool,
    /// With --leave-surface-out: which recognizer to train (the training options below apply
    /// only then).
    #[arg(long, value_enum, requires = "leave_surface_out")]
    method: Option<super::recognize_cmd::Method>,
    #[command(flatten)]
    training: super::recognize_cmd::TrainOptions,
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
    let read = |paths: &[PathBuf]| -> anyhow::Result<Vec<LabelledCapture>> {
        paths
            .iter()
            .map(|p| LabelledCapture::read(p).with_context(|| format!("reading capture {}", p.display())))
            .collect()
    };
    let (method, confusion) = match args.method {
        Some(method) => {
            let captures = read(&args.inputs)?;
            // One recognizer per surface, each with the given seed.
            let confusion = surface_confusion(&captures, |train, _| {
                super::recognize_cmd::train_model(method, &args.training, train, args.training.seed)
            })?;
            (
                format!("{} trained leaving each surface out", method.name()),
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
            let e = model.evaluate(&read(captures)?, None)?;
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
            Err(CategoryError::Disconnected { .. }) => ("mds".to_owned(), classical_mds::<2>(&distances)?),
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
    write_scatter(&args.out.join("mds.png"), &names, &points, &tree, &embedding)?;
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

/// Registers the bundled font with plotters once (the bitmap backend has no system fonts).
fn font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            epaint_default_fonts::UBUNTU_LIGHT,
        );
    });
}

/// Scatter of the embedded surfaces, labelled by name, coloured by leaf category.
fn write_scatter(
    path: &Path,
    names: &[String],
    points: &[[f64; 2]],
    tree: &CategoryTree,
    embedding: &str,
) -> anyhow::Result<()> {
    font();
    let (w, h) = (1100u32, 900u32);
    let mut rgb = vec![255u8; (w * h * 3) as usize];
    let mut leaf_of = vec![0usize; names.len()];
    for (leaf, members) in tree.leaves().iter().enumerate() {
        for &i in *members {
            if let Some(l) = leaf_of.get_mut(i) {
                *l = leaf;
            }
        }
    }
    let range = |axis: usize| {
        let (lo, hi) = points
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                (a.min(p[axis]), b.max(p[axis]))
            });
        // Room for the labels right of the points, and a usable range when all points coincide.
        let span = if hi > lo { hi - lo } else { 1.0 };
        (lo - 0.08 * span)..(hi + 0.25 * span)
    };
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        let plot = |e: String| anyhow::anyhow!("drawing {}: {e}", path.display());
        root.fill(&WHITE).map_err(|e| plot(e.to_string()))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!("surfaces by confusion similarity ({embedding})"),
                ("sans-serif", 24),
            )
            .margin(16)
            .x_label_area_size(36)
            .y_label_area_size(52)
            .build_cartesian_2d(range(0), range(1))
            .map_err(|e| plot(e.to_string()))?;
        chart
            .configure_mesh()
            .x_desc("dimension 1")
            .y_desc("dimension 2")
            .draw()
            .map_err(|e| plot(e.to_string()))?;
        let font = ("sans-serif", 16).into_font().color(&BLACK);
        let at: Vec<(i32, i32)> = points
            .iter()
            .map(|p| chart.backend_coord(&(p[0], p[1])))
            .collect();
        for (i, &(x, y)) in at.iter().enumerate() {
            let color = Palette99::pick(leaf_of[i]).to_rgba();
            root.draw(&Circle::new((x, y), 6, color.filled()))
                .map_err(|e| plot(e.to_string()))?;
        }
        let sizes = names
            .iter()
            .map(|n| {
                root.estimate_text_size(n, &font)
                    .map(|(w, h)| (w as i32, h as i32))
                    .map_err(|e| plot(e.to_string()))
            })
            .collect::<anyhow::Result<Vec<_>>>()?;
        let (plot_x, plot_y) = chart.plotting_area().get_pixel_range();
        for (i, (corner, leader)) in place_labels(&at, &sizes, (plot_x, plot_y))
            .into_iter()
            .enumerate()
        {
            if leader {
                let (w, h) = sizes[i];
                // To the nearest point of the label's box.
                let end = (
                    at[i].0.clamp(corner.0, corner.0 + w),
                    at[i].1.clamp(corner.1, corner.1 + h),
                );
                root.draw(&PathElement::new(vec![at[i], end], BLACK.mix(0.4)))
                    .map_err(|e| plot(e.to_string()))?;
            }
            root.draw(&Text::new(names[i].clone(), corner, font.clone()))
                .map_err(|e| plot(e.to_string()))?;
        }
        root.present().map_err(|e| plot(e.to_string()))?;
    }
    capture::write_atomically(path, |out| {
        let mut encoder = png::Encoder::new(out, w, h);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(std::io::Error::other)?;
        writer.write_image_data(&rgb).map_err(std::io::Error::other)?;
        writer.finish().map_err(std::io::Error::other)
    })
    .with_context(|| format!("writing {}", path.display()))
}

/// Top-left corners for the labels of the points `at` (pixels), each of `sizes`, so that no
/// label covers another label or a point where that can be helped, and whether each needs a
/// leader line back to its point (when it had to move away from it).
///
/// Greedy, points in order: each label tries positions beside its point, then on rings further
/// out, and takes the first that overlaps nothing and stays inside `area`, else the one with
/// the least overlap. Similar surfaces sit on top of each other in the embedding, so labels
/// placed at one fixed offset would print over each other; no plotting crate places labels.
fn place_labels(
    at: &[(i32, i32)],
    sizes: &[(i32, i32)],
    area: (std::ops::Range<i32>, std::ops::Range<i32>),
) -> Vec<((i32, i32), bool)> {
    const POINT: i32 = 7;
    const GAP: i32 = 9;
    let overlap = |a: (i32, i32, i32, i32), b: (i32, i32, i32, i32)| -> i64 {
        let w = (a.2.min(b.2) - a.0.max(b.0)).max(0);
        let h = (a.3.min(b.3) - a.1.max(b.1)).max(0);
        i64::from(w) * i64::from(h)
    };
    let points: Vec<(i32, i32, i32, i32)> = at
        .iter()
        .map(|&(x, y)| (x - POINT, y - POINT, x + POINT, y + POINT))
        .collect();
    let mut placed: Vec<(i32, i32, i32, i32)> = Vec::with_capacity(at.len());
    let mut out = Vec::with_capacity(at.len());
    for (i, (&(x, y), &(w, h))) in at.iter().zip(sizes).enumerate() {
        let mut best: Option<(i64, (i32, i32), bool)> = None;
        'rings: for ring in 0..8 {
            let r = ring * (h + 4);
            let candidates = [
                (x + GAP + r, y - h / 2),
                (x - GAP - w - r, y - h / 2),
                (x - w / 2, y - GAP - h - r),
                (x - w / 2, y + GAP + r),
                (x + GAP + r, y - GAP - h - r),
                (x + GAP + r, y + GAP + r),
                (x - GAP - w - r, y - GAP - h - r),
                (x - GAP - w - r, y + GAP + r),
            ];
            for (cx, cy) in candidates {
                let b = (cx, cy, cx + w, cy + h);
                let outside =
                    b.0 < area.0.start || b.2 > area.0.end || b.1 < area.1.start || b.3 > area.1.end;
                let cost: i64 = placed.iter().map(|p| overlap(*p, b)).sum::<i64>()
                    + points
                        .iter()
                        .enumerate()
                        .filter(|(j, _)| *j != i)
                        .map(|(_, p)| overlap(*p, b))
                        .sum::<i64>()
                    + if outside {
                        i64::from(w) * i64::from(h) * 4
                    } else {
                        0
                    };
                if best.is_none_or(|(c, _, _)| cost < c) {
                    best = Some((cost, (cx, cy), ring > 0));
                }
                if cost == 0 {
                    break 'rings;
                }
            }
        }
        let (_, corner, leader) = best.unwrap_or((0, (x + GAP, y - h / 2), false));
        placed.push((corner.0, corner.1, corner.0 + w, corner.1 + h));
        out.push((corner, leader));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_of_coinciding_points_do_not_overlap() {
        // Five surfaces on one spot and two close by, as similar surfaces land in the embedding.
        let at = [(300, 300); 5]
            .into_iter()
            .chain([(310, 305), (600, 200)])
            .collect::<Vec<_>>();
        let sizes = vec![(120, 16); at.len()];
        let placed = place_labels(&at, &sizes, (0..1000, 0..800));
        let boxes: Vec<_> = placed
            .iter()
            .zip(&sizes)
            .map(|(((x, y), _), (w, h))| (*x, *y, x + w, y + h))
            .collect();
        for (i, a) in boxes.iter().enumerate() {
            assert!(a.0 >= 0 && a.2 <= 1000 && a.1 >= 0 && a.3 <= 800, "{a:?}");
            for b in &boxes[i + 1..] {
                let apart = a.2 <= b.0 || b.2 <= a.0 || a.3 <= b.1 || b.3 <= a.1;
                assert!(apart, "{a:?} overlaps {b:?}");
            }
            for (j, p) in at.iter().enumerate() {
                let clear = p.0 + 7 <= a.0 || a.2 <= p.0 - 7 || p.1 + 7 <= a.1 || a.3 <= p.1 - 7;
                assert!(clear || j == i, "label {i} covers point {j}");
            }
        }
        // The lone point keeps its label beside it, without a leader.
        assert_eq!(placed[6], ((609, 192), false));
    }
    use haptics::sim::protocols::sinapov::scratch_capture;
    use haptics::sim::world::scratch::{Behaviour, household_surfaces};
    use recognize::knn::KnnParams;
    use recognize::spectral::CellScale;

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

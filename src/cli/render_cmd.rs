//! `palpus render`.

use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::Args;
use glam::DVec3;
use haptics::HapticSample;
use haptics::PunctureState;
use haptics::admittance_channel as channel;
use serde::Deserialize;

use crate::models;
use crate::scene::Scene;
use crate::session::{self, SegmentKind, start_position_m};
use crate::view::{SceneView, ViewState, overlay_plots};

/// Draw one frame of a scene headless, to PNG.
///
/// Without --state the tool waits at the task's start. A state file (JSON) poses it:
/// `{"object": "liver", "tool_position_m": [0, 0, -0.03], "law_state": "capsule_loading"}` —
/// device coordinates (z up, the surface at z = -0.02 m), law state one of approach,
/// capsule_loading, puncture, insertion, withdrawal. The models are resolved as `palpus run`
/// does (cached), because the frame shows the object the task works on.
#[derive(Debug, Args)]
pub(crate) struct RenderArgs {
    /// The scene file.
    scene: PathBuf,
    /// The PNG to write.
    #[arg(long, value_name = "FILE")]
    out: PathBuf,
    /// Image size.
    #[arg(long, default_value = "1280x720", value_parser = super::parse_size)]
    size: [u32; 2],
    /// Multisampling: 1 or 4.
    #[arg(long, default_value_t = 4)]
    msaa: u32,
    /// Draw the 3-D scene at this fraction (0.25 to 1) of the image's resolution and stretch it:
    /// faster on a software rasterizer, softer (`palpus bench render` shows the PSNR it costs).
    #[arg(long, default_value_t = 1.0)]
    scale: f32,
    /// The haptic state to draw (JSON).
    #[arg(long, value_name = "FILE")]
    state: Option<PathBuf>,
    /// Draw the overlay too.
    #[arg(long)]
    overlay: bool,
    /// Where identified models are cached.
    #[arg(long, value_name = "DIR")]
    cache_dir: Option<PathBuf>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct StateFile {
    object: Option<String>,
    tool_position_m: [f64; 3],
    #[serde(default)]
    law_state: Option<String>,
}

fn law_code(name: &str) -> Option<f64> {
    let s = match name {
        "approach" => PunctureState::Approach,
        "capsule_loading" => PunctureState::CapsuleLoading,
        "puncture" => PunctureState::Puncture,
        "insertion" => PunctureState::Insertion,
        "withdrawal" => PunctureState::Withdrawal,
        _ => return None,
    };
    Some(s.code())
}

pub(crate) fn run(args: &RenderArgs) -> anyhow::Result<()> {
    if args.msaa != 1 && args.msaa != 4 {
        bail!("--msaa {}: expected 1 or 4", args.msaa);
    }
    let scene = Scene::load(&args.scene)?;
    let cache_dir = args.cache_dir.clone().unwrap_or_else(models::default_cache_dir);
    let resolved = models::resolve_with_progress(&scene, &cache_dir)?;
    let segments = session::segments(&scene, &resolved)?;
    let view = SceneView::load(&scene)?;
    let mut sample = HapticSample::default();
    let mut object = segments.first().map(|s| s.object.clone());
    let mut position = start_position_m(&scene);
    let mut code = PunctureState::Approach.code();
    if let Some(path) = &args.state {
        let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        let state: StateFile = serde_json::from_str(&text)
            .map_err(|e| anyhow::anyhow!("{}:{}: {e}", path.display(), e.line()))?;
        if state.tool_position_m.iter().any(|v| !v.is_finite()) {
            bail!("{}: `tool_position_m` must be finite", path.display());
        }
        position = DVec3::from_array(state.tool_position_m);
        if let Some(name) = state.law_state {
            code = law_code(&name).with_context(|| {
                format!(
                    "{}: `law_state` `{name}`: expected approach, capsule_loading, puncture, insertion or withdrawal",
                    path.display()
                )
            })?;
        }
        if let Some(o) = state.object {
            if !segments.iter().any(|s| s.object == o) {
                bail!(
                    "{}: `object` `{o}` is not worked on in {}",
                    path.display(),
                    scene.name
                );
            }
            object = Some(o);
        }
    }
    let segment = segments.iter().find(|s| Some(&s.object) == object.as_ref());
    sample.state.position_m = position;
    sample.channels[channel::VIRTUAL_Z_M] = position.z;
    sample.channels[channel::ENV_STATE] = code;
    let kind: Option<&SegmentKind> = segment.map(|s| &s.kind);
    // A still frame shows one moment: a loading needle is pressing the intact surface.
    let state = ViewState {
        object: object.as_deref(),
        kind,
        sample: Some(&sample),
        surface_given: false,
    };
    let mut frame = view.frame(&state);
    if args.overlay {
        let mut overlay = overlay_plots(&[sample], kind, 10.0, 10);
        overlay.device_status = format!("{} (still frame)", scene.name);
        frame.overlay = Some(overlay);
    }
    let mut renderer = render::Renderer::headless(args.size[0], args.size[1], args.msaa)?;
    renderer.set_scale(args.scale)?;
    let image = renderer.render(&frame)?;
    image.save_png(&args.out)?;
    println!(
        "wrote {} ({}×{}, MSAA {}, {})",
        args.out.display(),
        image.width,
        image.height,
        renderer.msaa(),
        renderer.adapter_description()
    );
    Ok(())
}

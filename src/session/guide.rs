//! What a guided attempt's overlay says while the needle goes in: the phase the tip is in, in
//! the tissue's terms, and how far the target is (before it gives: to where the model makes it
//! give at the tip's speed; after: how far past it the tip is against the allowance). An exam
//! shows none of it until the attempt ends. Once the tip is out of the tissue, both tell how
//! the attempt did, until the next one starts.

use haptics::admittance_channel as c;
use haptics::{HapticSample, PunctureState};
use identify::{ModelBody, PhaseModel};
use render::TaskPanel;

use super::SegmentKind;
use super::score::Score;
use crate::scene::{Goal, GoalMode, in_words};

/// One line of guidance, and whether it warns (the tip past the allowance, a forbidden layer
/// given).
#[derive(Debug, Clone, PartialEq)]
pub struct GuideLine {
    /// The text.
    pub text: String,
    /// Drawn as a warning.
    pub warning: bool,
}

/// Follows one attempt sample by sample (the haptic thread's samples, in order) for the
/// overlay. Allocates only when a layer gives.
#[derive(Debug, Clone, Default)]
pub struct LiveGuide {
    state: Option<PunctureState>,
    /// Depth at which each layer gave, in order, m.
    given_m: Vec<f64>,
    depth_m: f64,
    speed_mps: f64,
    deepest_m: f64,
    /// The last finished attempt's number and score.
    last: Option<(usize, Score)>,
}

impl LiveGuide {
    /// A guide for a new attempt.
    pub fn new() -> Self {
        Self::default()
    }

    /// Takes the next sample (tissue surface at `surface_z_m`).
    pub fn push(&mut self, sample: &HapticSample, surface_z_m: f64) {
        let state = PunctureState::from_code(sample.channels[c::ENV_STATE]);
        let depth_m = surface_z_m - sample.channels[c::VIRTUAL_Z_M];
        if state == Some(PunctureState::Puncture) && self.state != Some(PunctureState::Puncture) {
            self.given_m.push(sample.channels[c::ENV_INPUT]);
        }
        self.state = state;
        self.depth_m = depth_m;
        self.speed_mps = -sample.channels[c::VIRTUAL_VZ_MPS];
        self.deepest_m = self.deepest_m.max(depth_m);
    }

    /// Attempt `number` has ended with `score` (the tip left the tissue): the next stroke is a
    /// new attempt, and the overlay tells how this one did.
    pub fn attempt_ended(&mut self, number: usize, score: Score) {
        *self = Self {
            last: Some((number, score)),
            ..Self::default()
        };
    }

    /// The last finished attempt's line, while no other is under way.
    fn last_line(&self) -> Option<GuideLine> {
        let (number, score) = self.last.as_ref().filter(|_| self.depth_m <= 0.0)?;
        Some(GuideLine {
            text: format!(
                "Attempt {number}: {} — {}",
                if score.passed { "passed" } else { "failed" },
                score.verdict
            ),
            warning: !score.passed,
        })
    }

    /// How many layers have given in this attempt.
    pub fn layers_given(&self) -> usize {
        self.given_m.len()
    }

    /// The overlay's lines for `goal`, with the phase model's layers (when the scene renders
    /// one) to say where the target will give.
    pub fn lines(&self, goal: &Goal, model: Option<&PhaseModel>) -> Vec<GuideLine> {
        let layer = |k: usize| {
            goal.layers
                .get(k)
                .map_or_else(|| format!("layer {}", k + 1), |l| in_words(l))
        };
        let given = self.given_m.len();
        let mm = |m: f64| m * 1e3;
        let phase = match self.state {
            None | Some(PunctureState::Approach) if self.depth_m <= 0.0 => "above the tissue".to_owned(),
            Some(PunctureState::CapsuleLoading) => format!("pressing the {}", layer(given)),
            Some(PunctureState::Puncture) => format!("the {} gives", layer(given.saturating_sub(1))),
            Some(PunctureState::Withdrawal) => "withdrawing".to_owned(),
            _ if given == 0 => "in the tissue".to_owned(),
            _ => format!("through the {}", layer(given - 1)),
        };
        let mut out = vec![GuideLine {
            text: format!("Tip: {phase}, {:.1} mm deep", mm(self.depth_m.max(0.0))),
            warning: false,
        }];
        let target = goal.layer_index(&goal.stop_after).unwrap_or(0);
        let name = layer(target);
        match self.given_m.get(target) {
            Some(&gave_m) => {
                let past_m = (self.deepest_m - gave_m).max(0.0);
                out.push(GuideLine {
                    text: format!(
                        "Target: the {name} gave at {:.1} mm; {:.1} mm past it, {:.1} mm allowed",
                        mm(gave_m),
                        mm(past_m),
                        mm(goal.within_m)
                    ),
                    warning: past_m > goal.within_m,
                });
            }
            None => {
                let at_m = model
                    .and_then(|m| m.layers.get(target))
                    .map(|l| l.contact_depth_m + l.threshold.deflection_m(self.speed_mps.max(0.0)));
                let text = match at_m {
                    Some(at_m) => format!(
                        "Target: the {name} gives at about {:.1} mm at this speed, {:.1} mm to go",
                        mm(at_m),
                        mm((at_m - self.depth_m).max(0.0))
                    ),
                    None => format!(
                        "Target: the {name}, not yet given ({given} of {} layers given)",
                        target + 1
                    ),
                };
                out.push(GuideLine { text, warning: false });
            }
        }
        for forbidden in &goal.must_not_puncture {
            if goal.layer_index(forbidden).is_some_and(|k| k < given) {
                out.push(GuideLine {
                    text: format!("The {} was punctured", in_words(forbidden)),
                    warning: true,
                });
            }
        }
        out.extend(self.last_line());
        out
    }
}

/// The overlay's task panel for a segment of `kind` under `goal` (none without a goal or away
/// from a needle): the guide's lines, or an exam's one line.
pub fn task_panel(goal: Option<&Goal>, kind: Option<&SegmentKind>, guide: &LiveGuide) -> TaskPanel {
    match (goal, kind) {
        (Some(goal), Some(SegmentKind::Needle { model, .. })) => {
            let phases = match &model.body {
                ModelBody::Phases(p) => Some(p.as_ref()),
                _ => None,
            };
            needle_panel(goal, phases, guide)
        }
        _ => TaskPanel::None,
    }
}

/// [`task_panel`] of a needle segment rendering `phases` (when a phase model).
fn needle_panel(goal: &Goal, phases: Option<&PhaseModel>, guide: &LiveGuide) -> TaskPanel {
    match goal.mode {
        GoalMode::Exam => TaskPanel::Exam(guide.last_line().map_or_else(
            || {
                format!(
                    "Exam: no readings until the attempt ends. Stop within {:.1} mm past the {}.",
                    goal.within_m * 1e3,
                    in_words(&goal.stop_after)
                )
            },
            |l| l.text,
        )),
        GoalMode::Guided => TaskPanel::Guided(
            guide
                .lines(goal, phases)
                .into_iter()
                .map(|l| (l.text, l.warning))
                .collect(),
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn goal() -> Goal {
        Goal::guided_through(&["capsule", "vessel_wall"], 0.003)
    }

    /// A sample with the tip `depth_mm` below a surface at z = 0, advancing at 10 mm/s, in
    /// `state`.
    fn at(depth_mm: f64, state: PunctureState) -> HapticSample {
        let mut s = HapticSample::default();
        s.channels[c::VIRTUAL_Z_M] = -depth_mm * 1e-3;
        s.channels[c::VIRTUAL_VZ_MPS] = -0.01;
        s.channels[c::ENV_STATE] = state.code();
        s.channels[c::ENV_INPUT] = depth_mm * 1e-3;
        s
    }

    fn texts(guide: &LiveGuide, goal: &Goal) -> Vec<String> {
        guide.lines(goal, None).into_iter().map(|l| l.text).collect()
    }

    #[test]
    fn the_guide_names_the_phase_and_the_distance_past_the_target() {
        let goal = goal();
        let mut guide = LiveGuide::new();
        guide.push(&at(-1.0, PunctureState::Approach), 0.0);
        assert_eq!(texts(&guide, &goal)[0], "Tip: above the tissue, 0.0 mm deep");
        guide.push(&at(5.0, PunctureState::CapsuleLoading), 0.0);
        assert_eq!(
            texts(&guide, &goal),
            [
                "Tip: pressing the capsule, 5.0 mm deep",
                "Target: the vessel wall, not yet given (0 of 2 layers given)"
            ]
        );
        guide.push(&at(12.0, PunctureState::Puncture), 0.0);
        guide.push(&at(15.0, PunctureState::Insertion), 0.0);
        assert_eq!(texts(&guide, &goal)[0], "Tip: through the capsule, 15.0 mm deep");
        guide.push(&at(21.0, PunctureState::CapsuleLoading), 0.0);
        assert_eq!(
            texts(&guide, &goal)[0],
            "Tip: pressing the vessel wall, 21.0 mm deep"
        );
        guide.push(&at(23.0, PunctureState::Puncture), 0.0);
        guide.push(&at(25.0, PunctureState::Insertion), 0.0);
        let lines = guide.lines(&goal, None);
        assert_eq!(
            lines[1].text,
            "Target: the vessel wall gave at 23.0 mm; 2.0 mm past it, 3.0 mm allowed"
        );
        assert!(!lines[1].warning);
        // Past the allowance, and still so after backing off: the deepest point counts.
        guide.push(&at(27.0, PunctureState::Insertion), 0.0);
        guide.push(&at(24.0, PunctureState::Withdrawal), 0.0);
        let lines = guide.lines(&goal, None);
        assert_eq!(lines[0].text, "Tip: withdrawing, 24.0 mm deep");
        assert!(
            lines[1].warning && lines[1].text.contains("4.0 mm past it"),
            "{lines:?}"
        );
        // A layer that must not give, given: a warning line of its own.
        let strict = Goal {
            stop_after: "capsule".into(),
            must_not_puncture: vec!["vessel_wall".into()],
            ..goal.clone()
        };
        let lines = guide.lines(&strict, None);
        assert_eq!(
            lines.last().map(|l| (l.text.as_str(), l.warning)),
            Some(("The vessel wall was punctured", true))
        );
    }

    /// A phase model of two membranes meeting the tip at 0 and 20 mm, each giving 3 mm later
    /// at any speed.
    fn two_membranes() -> PhaseModel {
        let shaft = r#"{"constant_n": 0.1, "per_depth_npm": 0.0, "per_speed_nspm": 0.0,
            "per_depth_speed_nspm2": 0.0, "domain": {"depth_m": [0.0, 0.05], "velocity_mps": [0.001, 0.01]}}"#;
        let layer = |contact_m: f64| {
            format!(
                r#"{{"contact_depth_m": {contact_m}, "loading": {{"offset_n": 0.0, "a1_npm": 50.0, "a2_npm2": 0.0,
                "damping_nspm": 0.0, "domain": {{"depth_m": [0.0, 0.05], "velocity_mps": [0.001, 0.01]}}}},
                "threshold": {{"coefficients": [0.003], "speed_mps": [0.001, 0.01], "rms_m": 0.0}},
                "after": {shaft}, "events": 3, "peak_force_n": 1.0}}"#
            )
        };
        serde_json::from_str(&format!(
            r#"{{"layers": [{}, {}], "withdrawal": {shaft}, "hold_band_mps": 0.0005}}"#,
            layer(0.0),
            layer(0.02)
        ))
        .expect("a phase model")
    }

    #[test]
    fn with_the_phase_model_the_guide_says_where_the_target_will_give() {
        let goal = goal();
        let model = two_membranes();
        let mut guide = LiveGuide::new();
        guide.push(&at(15.0, PunctureState::Insertion), 0.0);
        let lines = guide.lines(&goal, Some(&model));
        assert_eq!(
            lines[1].text,
            "Target: the vessel wall gives at about 23.0 mm at this speed, 8.0 mm to go"
        );
    }

    #[test]
    fn an_exam_shows_one_line_and_a_goalless_or_rubbing_scene_none() {
        let mut goal = goal();
        let guide = LiveGuide::new();
        assert!(matches!(needle_panel(&goal, None, &guide), TaskPanel::Guided(l) if l.len() == 2));
        goal.mode = GoalMode::Exam;
        assert!(matches!(
            needle_panel(&goal, None, &guide),
            TaskPanel::Exam(l) if l.contains("3.0 mm past the vessel wall")
        ));
        let rub = SegmentKind::Surface {
            surface: "styrol_rough".into(),
        };
        assert_eq!(task_panel(Some(&goal), Some(&rub), &guide), TaskPanel::None);
        assert_eq!(task_panel(None, None, &guide), TaskPanel::None);
    }

    #[test]
    fn a_finished_attempt_is_told_until_the_next_one_starts_even_in_an_exam() {
        let mut goal = goal();
        goal.mode = GoalMode::Exam;
        let mut guide = LiveGuide::new();
        guide.push(&at(24.0, PunctureState::Insertion), 0.0);
        let failed = Score {
            passed: false,
            verdict: "went 5.0 mm past where the vessel wall gave at 23.0 mm (allowed 3.0 mm)".into(),
            target: "vessel_wall".into(),
            layers_given: vec!["capsule".into(), "vessel_wall".into()],
            target_depth_m: Some(0.023),
            overshoot_m: Some(0.005),
            allowed_overshoot_m: 0.003,
            peak_force_n: 1.5,
            time_to_target_s: Some(2.0),
            withdrawals: 0,
            reinsertions: 0,
            smoothness_sparc: None,
            deepest_m: 0.028,
        };
        guide.attempt_ended(1, failed);
        guide.push(&at(-1.0, PunctureState::Approach), 0.0);
        assert_eq!(guide.layers_given(), 0, "the next stroke starts afresh");
        let told =
            "Attempt 1: failed — went 5.0 mm past where the vessel wall gave at 23.0 mm (allowed 3.0 mm)";
        assert_eq!(needle_panel(&goal, None, &guide), TaskPanel::Exam(told.into()));
        goal.mode = GoalMode::Guided;
        assert!(
            matches!(needle_panel(&goal, None, &guide), TaskPanel::Guided(l) if l.last() == Some(&(told.to_owned(), true)))
        );
        // Back in the tissue: the exam hides everything again.
        goal.mode = GoalMode::Exam;
        guide.push(&at(2.0, PunctureState::CapsuleLoading), 0.0);
        assert!(matches!(needle_panel(&goal, None, &guide), TaskPanel::Exam(l) if l.starts_with("Exam:")));
    }
}

//! `[task.goal]`: what an insertion attempt must achieve, and its checks.

use std::path::PathBuf;

use serde::Deserialize;

use super::{MAX_TASK_S, Scene, SceneError};

/// `[task.goal]`: what an insertion attempt must achieve, in the tissue's terms: the layers the
/// needle meets, in order, named as the scene names them; the one after whose giving the tip
/// must stop, and how far past where it gave; what fails the attempt.
///
/// ```toml
/// [task.goal]
/// layers = ["capsule", "vessel_wall"]   # the model's membranes, shallowest first
/// stop_after = "vessel_wall"             # stop after this one gives ...
/// within_m = 0.003                       # ... no deeper than 3 mm past where it gave
/// must_not_puncture = []                 # layers whose giving fails the attempt
/// max_force_n = 4.0                      # an axial force over this fails it
/// time_limit_s = 20.0                    # from first contact to the target giving
/// reference = "expert.csv"               # an expert's recorded attempt, drawn under each
/// mode = "guided"                        # or "exam": no guidance in the window until the end
/// ```
#[derive(Debug, Clone, Deserialize, PartialEq, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct Goal {
    /// The layers (membranes) the needle meets, shallowest first: the n-th to give is
    /// `layers[n]`.
    pub layers: Vec<String>,
    /// The layer after whose giving the tip must stop.
    pub stop_after: String,
    /// How far past the depth where `stop_after` gave the tip may go, m.
    pub within_m: f64,
    /// Layers whose giving fails the attempt (all deeper than `stop_after`).
    #[serde(default)]
    pub must_not_puncture: Vec<String>,
    /// An axial force over this fails the attempt, N.
    #[serde(default)]
    pub max_force_n: Option<f64>,
    /// The target must give within this long of first contact, s.
    #[serde(default)]
    pub time_limit_s: Option<f64>,
    /// An expert's attempt (an insertion capture, as `palpus run --record` writes one), drawn
    /// under each attempt's force against depth.
    #[serde(default)]
    pub reference: Option<PathBuf>,
    /// What the window's overlay shows during an attempt.
    #[serde(default)]
    pub mode: GoalMode,
}

/// `task.goal.mode`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case", try_from = "String")]
pub enum GoalMode {
    /// The phase the tip is in and the distance to the target, live.
    #[default]
    Guided,
    /// Nothing (not even the force plots) until the attempt ends, then its score.
    Exam,
}

impl TryFrom<String> for GoalMode {
    type Error = String;

    // By hand so that the message names the key: inside `[task]` the parser's own points at
    // the table, not the line.
    fn try_from(name: String) -> Result<Self, String> {
        match name.as_str() {
            "guided" => Ok(Self::Guided),
            "exam" => Ok(Self::Exam),
            other => Err(format!(
                "task.goal.mode: `{other}` is neither `guided` nor `exam`"
            )),
        }
    }
}

/// A layer's name as words (`vessel_wall` → `vessel wall`), as scores and guidance say it.
pub fn in_words(layer: &str) -> String {
    layer.replace('_', " ")
}

#[cfg(test)]
impl Goal {
    /// A guided goal over `layers`, stopping within `within_m` after the last, with no limits:
    /// what the session tests score against.
    pub(crate) fn guided_through(layers: &[&str], within_m: f64) -> Self {
        Self {
            layers: layers.iter().map(|l| (*l).to_owned()).collect(),
            stop_after: layers.last().map_or_else(String::new, |l| (*l).to_owned()),
            within_m,
            must_not_puncture: Vec::new(),
            max_force_n: None,
            time_limit_s: None,
            reference: None,
            mode: GoalMode::Guided,
        }
    }
}

impl Goal {
    /// The index of `layer` in [`Goal::layers`].
    pub fn layer_index(&self, layer: &str) -> Option<usize> {
        self.layers.iter().position(|l| l == layer)
    }
}

impl Scene {
    pub(super) fn validate_goal(&self, goal: &Goal) -> Result<(), SceneError> {
        let key = |field: &str| format!("task.goal.{field}");
        if goal.layers.is_empty() {
            return Err(self.invalid(
                key("layers"),
                "name the layers the needle meets, shallowest first",
            ));
        }
        for (i, layer) in goal.layers.iter().enumerate() {
            if layer.trim().is_empty() {
                return Err(self.invalid(format!("task.goal.layers[{i}]"), "an empty name"));
            }
            if goal.layers[..i].contains(layer) {
                return Err(self.invalid(
                    format!("task.goal.layers[{i}]"),
                    format!("`{layer}` is named twice"),
                ));
            }
        }
        let known = |field: &str, layer: &str| {
            goal.layer_index(layer).ok_or_else(|| {
                self.invalid(
                    key(field),
                    format!(
                        "`{layer}` is not one of task.goal.layers ({})",
                        goal.layers.join(", ")
                    ),
                )
            })
        };
        let target = known("stop_after", &goal.stop_after)?;
        for layer in &goal.must_not_puncture {
            if known("must_not_puncture", layer)? <= target {
                return Err(self.invalid(
                    key("must_not_puncture"),
                    format!(
                        "`{layer}` lies no deeper than `{}`, which must give: no attempt could pass",
                        goal.stop_after
                    ),
                ));
            }
        }
        if !(goal.within_m.is_finite() && goal.within_m > 0.0 && goal.within_m <= 0.05) {
            return Err(self.invalid(
                key("within_m"),
                format!("{}: expected more than 0 and at most 0.05 m", goal.within_m),
            ));
        }
        if let Some(f) = goal.max_force_n {
            self.in_range(
                &key("max_force_n"),
                f,
                self.device_choice()?.backend().specs.max_force_n,
                "the device's largest force",
            )?;
        }
        if let Some(t) = goal.time_limit_s {
            self.in_range(&key("time_limit_s"), t, MAX_TASK_S, "the longest task")?;
        }
        Ok(())
    }
}

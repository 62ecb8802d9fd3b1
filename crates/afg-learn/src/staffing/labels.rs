//! The staffing model's labelled games: each a scarce team game, its tasks' features
//! and the staffing of its best assignment found, kept one per line in the run
//! directory so that a stopped labelling resumes.

use std::path::Path;
use std::time::Duration;

use afg_baseline::TeamOptimum;
use afg_game::{GameSize, GeneratorKnobs, Instance, SkillDraw};
use serde::{Deserialize, Serialize};

use super::features::STAFF_FEATURES;
use super::staffing_features;
use crate::LearnError;

/// The file of a run's labelled games, one [`LabelledGame`] per line.
pub const LABELS_FILE_NAME: &str = "labels.jsonl";

/// The scarce team game of `size` and `seed`: thresholds uniform in [N/M, 2N/M] and,
/// with `skills`, skills drawn so (as `afg gen --robots N --tasks M --min-team
/// N/M,2N/M --seed S`, with `--skills S --skill-share P --requires LO,HI`).
///
/// # Errors
/// Errors of the generator.
pub fn scarce_game(
    size: GameSize,
    skills: Option<SkillDraw>,
    seed: u64,
) -> Result<Instance, LearnError> {
    let knobs = GeneratorKnobs {
        min_team: Some(size.scarce_thresholds()),
        skills: skills.map(|d| d.count),
        skill_share: skills.map(|d| d.share),
        requires: skills.map(|d| (d.requires.min, d.requires.max)),
        ..GeneratorKnobs::default()
    };
    Ok(knobs.config(size.robots, size.tasks, seed)?.generate()?)
}

/// One labelled game: its seed and size, every task's features and label (1: earning
/// in the best assignment found, its team complete and holding its skills), and that
/// assignment's welfare.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LabelledGame {
    /// The generator seed.
    pub seed: u64,
    /// Its size.
    pub size: GameSize,
    /// `[M, STAFF_FEATURES]`.
    pub features: Vec<f32>,
    /// `[M]`, 0 or 1.
    pub labels: Vec<f32>,
    /// `[M]`, each task's threshold.
    pub thresholds: Vec<usize>,
    /// The welfare of the labelling assignment.
    pub welfare: f64,
    /// Whether it is proven optimal.
    pub proven: bool,
}

pub(super) fn label(
    size: GameSize,
    skills: Option<SkillDraw>,
    seed: u64,
    limit: Duration,
) -> Result<LabelledGame, LearnError> {
    let inst = scarce_game(size, skills, seed)?;
    let best = TeamOptimum {
        time_limit: Some(limit),
        ..TeamOptimum::default()
    }
    .solve(&inst)
    .map_err(|e| LearnError::InvalidConfig(e.to_string()))?;
    let labels = (inst.earning_tasks(&best.assignment).into_iter())
        .map(|earns| f32::from(u8::from(earns)))
        .collect();
    Ok(LabelledGame {
        seed,
        size,
        features: staffing_features(&inst, &TeamOptimum::relax(&inst)),
        labels,
        thresholds: inst.task_ids().map(|j| inst.min_team(j)).collect(),
        welfare: best.welfare,
        proven: best.proven,
    })
}

pub(super) fn lines_of(games: &[LabelledGame]) -> String {
    games
        .iter()
        .map(|g| serde_json::to_string(g).expect("a game serialises") + "\n")
        .collect()
}

pub(super) fn read_labels(path: &Path) -> Result<Vec<LabelledGame>, LearnError> {
    let error = |reason: String| LearnError::RunFile {
        path: path.display().to_string(),
        reason,
    };
    let text = std::fs::read_to_string(path).map_err(|e| error(e.to_string()))?;
    text.lines()
        .enumerate()
        .map(|(i, line)| {
            let game: LabelledGame =
                serde_json::from_str(line).map_err(|e| error(format!("line {}: {e}", i + 1)))?;
            let m = game.size.tasks;
            if game.features.len() != m * STAFF_FEATURES
                || game.labels.len() != m
                || game.thresholds.len() != m
            {
                return Err(error(format!(
                    "line {}: not {m} tasks' features and labels",
                    i + 1
                )));
            }
            Ok(game)
        })
        .collect()
}

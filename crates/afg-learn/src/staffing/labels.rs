//! The staffing model's labelled games: each a scarce team game, its tasks' features
//! and the staffing of its best assignment found, kept one per line in the run
//! directory so that a stopped labelling resumes.

use std::path::Path;
use std::time::Duration;

use afg_baseline::TeamOptimum;
use afg_game::{Family, GameSize, GeneratorKnobs, Instance, SkillDraw};
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

/// Which game a training run draws: the scarce game, or a named family's, of a size
/// and seed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct GameDraw {
    /// The named family (`None`: the scarce game, with the run's skills).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub family: Option<Family>,
    /// The generator seed.
    pub seed: u64,
    /// Its size.
    pub size: GameSize,
}

impl GameDraw {
    /// The game: the family's, or the scarce game with `skills`.
    ///
    /// # Errors
    /// Errors of the generator.
    ///
    /// # Examples
    /// ```
    /// use afg_game::{Family, GameSize};
    /// use afg_learn::staffing::GameDraw;
    /// let size = GameSize { robots: 30, tasks: 5 };
    /// let draw = GameDraw { family: Some(Family::Constant), seed: 1, size };
    /// let inst = draw.game(None)?;
    /// assert!(inst.task_ids().all(|j| inst.min_team(j) == 9)); // ⌈1.5 N/M⌉
    /// # Ok::<(), afg_learn::LearnError>(())
    /// ```
    pub fn game(self, skills: Option<SkillDraw>) -> Result<Instance, LearnError> {
        match self.family {
            None => scarce_game(self.size, skills, self.seed),
            Some(family) => Ok(family
                .config(self.size.robots, self.size.tasks, self.seed)?
                .generate()?),
        }
    }
}

/// One labelled game: which game it is, every task's features and label (1: earning
/// in the best assignment found, its team complete and holding its skills), and that
/// assignment's welfare.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LabelledGame {
    /// Which game it is (written as its own fields: `family`, `seed`, `size`).
    #[serde(flatten)]
    pub draw: GameDraw,
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
    inst: &Instance,
    draw: GameDraw,
    limit: Duration,
) -> Result<LabelledGame, LearnError> {
    let best = TeamOptimum {
        time_limit: Some(limit),
        ..TeamOptimum::default()
    }
    .solve(inst)
    .map_err(|e| LearnError::InvalidConfig(e.to_string()))?;
    let labels = (inst.earning_tasks(&best.assignment).into_iter())
        .map(|earns| f32::from(u8::from(earns)))
        .collect();
    Ok(LabelledGame {
        draw,
        features: staffing_features(inst, &TeamOptimum::relax(inst)),
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
            let m = game.draw.size.tasks;
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

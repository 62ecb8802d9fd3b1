//! A drawn mission's configuration: its preset and every knob, resolved to numbers, so
//! that a mission file records exactly what produced it (the drawing itself is in
//! `generate.rs`; a `Mission` keeps the configuration that drew it).

use afg_game::{CountRange, SkillDraw};
use serde::{Deserialize, Serialize};

/// How tasks arrive (and robots fail).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Preset {
    /// Every task at time 0: the first decision is the static game itself.
    Static,
    /// `waves` equal waves of tasks, one every `interval`, the first at 0.
    Waves,
    /// Arrivals at rate λ (`rate`), the first at 0.
    Poisson,
    /// Waves of tasks, and a share (`fail_share`) of the robots fails at uniformly
    /// random times.
    Attrition,
}

impl afg_game::Named for Preset {
    const ALL: &'static [Self] = &[
        Preset::Static,
        Preset::Waves,
        Preset::Poisson,
        Preset::Attrition,
    ];
    const WHAT: &'static str = "preset";

    fn name(self) -> &'static str {
        match self {
            Preset::Static => "static",
            Preset::Waves => "waves",
            Preset::Poisson => "poisson",
            Preset::Attrition => "attrition",
        }
    }
}

/// Every knob of a generated mission ([`MissionConfig::new`] sets the defaults).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MissionConfig {
    /// How tasks arrive.
    pub preset: Preset,
    /// Robots N.
    pub robots: usize,
    /// Tasks K over the whole mission.
    pub tasks: usize,
    /// Seed of the ChaCha8 generator.
    pub seed: u64,
    /// Workloads are uniform in `[workload_min, workload_max]`.
    pub workload_min: f64,
    /// See `workload_min`.
    pub workload_max: f64,
    /// Every robot's speed.
    pub speed: f64,
    /// The arena's side: positions are uniform in `[0, arena]²`.
    pub arena: f64,
    /// The mission ends here at the latest.
    pub horizon: f64,
    /// Waves of tasks (`waves`, `attrition`).
    pub waves: usize,
    /// Time between waves.
    pub interval: f64,
    /// Arrivals per time unit (`poisson`).
    pub rate: f64,
    /// Share of the robots that fail (`attrition`).
    pub fail_share: f64,
    /// Robots may idle (the void task) when no task is worth their trip.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub allow_void: bool,
    /// Task capacities drawn as the instance generator's `capacity_slack` does (over
    /// all K tasks: at any moment the open ones may hold fewer robots than there are,
    /// and the others idle); `None`: unbounded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub capacity_slack: Option<f64>,
    /// Task thresholds (`min_team`) uniform in this range, as the instance generator
    /// draws them; `None`: every task done by one robot.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_team: Option<CountRange>,
    /// Robot skills and task requirements, as the instance generator draws them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub skills: Option<SkillDraw>,
}

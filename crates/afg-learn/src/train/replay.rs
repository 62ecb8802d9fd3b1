//! Episodes as the replay buffer keeps them: the instance seed and the actions taken;
//! instances and graphs are rebuilt from the seed.

use std::sync::OnceLock;

use afg_baseline::Optimum;
use afg_game::{Assignment, Instance, RobotId, TaskId};
use afg_graph::{GraphKind, RobotGraph, Units};
use serde::{Deserialize, Serialize};

use super::TrainConfig;
use crate::LearnError;

/// One episode as stored: the instance seed and the actions taken.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct EpisodeRecord {
    pub(super) seed: u64,
    pub(super) actions: Vec<u8>,
}

/// An episode with its instance and graph rebuilt (not stored in checkpoints).
pub(super) struct Episode {
    pub(super) record: EpisodeRecord,
    pub(super) instance: Instance,
    pub(super) graph: RobotGraph,
    /// The instance's exact task prices, centred, in the welfare unit: computed on first
    /// use by the price loss ([`Episode::centred_prices`]).
    prices: OnceLock<Vec<f32>>,
}

impl Episode {
    pub(super) fn new(config: &TrainConfig, record: EpisodeRecord) -> Result<Self, LearnError> {
        let instance = config.instance(record.seed);
        let graph = RobotGraph::build(instance.robots(), GraphKind::default())?;
        Ok(Episode {
            record,
            instance,
            graph,
            prices: OnceLock::new(),
        })
    }

    /// The exact prices of the instance's tasks ([`Optimum::with_prices`]) minus their
    /// mean, divided by the welfare unit of `units`; one min-cost flow the first time.
    pub(super) fn centred_prices(&self, units: Units) -> &[f32] {
        self.prices.get_or_init(|| {
            let (_, exact) = Optimum.with_prices(&self.instance);
            let mean = exact.iter().sum::<f64>() / exact.len() as f64;
            let unit = units.welfare_unit(&self.instance);
            exact.iter().map(|p| ((p - mean) / unit) as f32).collect()
        })
    }

    /// The assignment after the first `t` actions.
    pub(super) fn assignment_after(&self, t: usize) -> Assignment {
        let mut a = Assignment::unassigned(self.instance.num_robots(), self.instance.num_tasks());
        for (i, &task) in self.record.actions[..t].iter().enumerate() {
            a.set(RobotId(i as u32), Some(TaskId(u32::from(task))));
        }
        a
    }
}

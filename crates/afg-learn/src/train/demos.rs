//! Learning from demonstrations (ours): the optimum's episodes in the replay, and the
//! large-margin terms that make the expert's action the best by a margin.

use super::config::{Demonstrations, TrainConfig};
use super::replay::{Episode, EpisodeRecord};
use crate::LearnError;

/// The expert episodes of a run's demonstrations (none without them).
pub(super) fn demonstrations(config: &TrainConfig) -> Result<Vec<Episode>, LearnError> {
    use afg_baseline::{Allocator, Optimum};
    let Some(d) = &config.demonstrations else {
        return Ok(Vec::new());
    };
    (0..d.episodes as u64)
        .map(|k| {
            let seed = Demonstrations::instance_seed(config.seed, k);
            let instance = config.instance(seed);
            let optimum = Optimum
                .allocate(&instance)
                .map_err(|e| LearnError::InvalidConfig(format!("demonstration {k}: {e}")))?
                .assignment;
            let actions = optimum
                .tasks()
                .iter()
                .map(|t| t.expect("the optimum places every robot").0 as u8)
                .collect();
            Episode::new(config, EpisodeRecord { seed, actions })
        })
        .collect()
}

/// The large-margin terms of demonstration rows whose action masks are `mask`
/// (`[rows, M]`) and whose expert actions are `experts`: `margin` for every other task
/// with room, 0 for the expert's, and a large negative number for full tasks, so that
/// the maximum runs over the tasks with room. `[rows, M]`.
pub(super) fn large_margins(mask: &[bool], experts: &[i64], m: usize, margin: f64) -> Vec<f32> {
    experts
        .iter()
        .zip(mask.chunks_exact(m))
        .flat_map(|(&expert, row)| {
            row.iter().enumerate().map(move |(j, &open)| {
                if !open {
                    -1e9
                } else if j as i64 == expert {
                    0.0
                } else {
                    margin as f32
                }
            })
        })
        .collect()
}

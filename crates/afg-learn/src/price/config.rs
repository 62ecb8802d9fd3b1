//! The settings of a price-model training run.

use serde::{Deserialize, Serialize};

use super::net::PriceNetConfig;
use crate::LearnError;

/// Every setting of a price-model training run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PriceTrainConfig {
    /// Robots per training instance N.
    pub robots: usize,
    /// Tasks per training instance M.
    pub tasks: usize,
    /// The network and its initialisation seed.
    pub network: PriceNetConfig,
    /// DAgger rounds.
    pub rounds: usize,
    /// Instances rolled out per round.
    pub episodes_per_round: usize,
    /// Adam steps per round.
    pub steps_per_round: usize,
    /// States per Adam step.
    pub batch: usize,
    /// Adam learning rate at the start; it falls linearly to a tenth over the run.
    pub lr: f64,
    /// Share of the model's own steps replaced by a random task.
    pub explore: f64,
    /// The expert acts with probability `expert_decay^round`.
    pub expert_decay: f64,
    /// States kept for training (oldest dropped).
    pub buffer_states: usize,
    /// Weight of the one-shot loss: the squared error of the centred prices of each
    /// training instance's empty state against its exact prices
    /// ([`afg_baseline::Optimum::with_prices`]); 0 trains on Q\* alone.
    pub one_shot_weight: f64,
    /// Size of the fixed validation set (the same seeds as the DQN trainer's).
    pub validation_instances: usize,
    /// Seed of everything random in the run.
    pub seed: u64,
}

impl PriceTrainConfig {
    /// The defaults (docs/price.md): width 64, 40 rounds of 32 instances and 100 Adam
    /// steps of 256 states, lr 1e-3, 10 % exploration, expert share halved each round.
    pub fn new(robots: usize, tasks: usize, seed: u64) -> Self {
        PriceTrainConfig {
            robots,
            tasks,
            network: PriceNetConfig { hidden: 64, seed },
            rounds: 40,
            episodes_per_round: 32,
            steps_per_round: 100,
            batch: 256,
            lr: 1e-3,
            explore: 0.1,
            expert_decay: 0.5,
            buffer_states: 200_000,
            one_shot_weight: 1.0,
            validation_instances: 32,
            seed,
        }
    }

    pub(super) fn validate(&self) -> Result<(), LearnError> {
        let bad = |what: &str| Err(LearnError::InvalidConfig(what.to_string()));
        if self.robots == 0 || self.tasks == 0 {
            return bad("N and M must be at least 1");
        }
        if self.network.hidden == 0 || self.rounds == 0 || self.episodes_per_round == 0 {
            return bad("width, rounds and episodes per round must be at least 1");
        }
        if self.batch == 0 || self.buffer_states == 0 || self.validation_instances == 0 {
            return bad("batch, buffer and validation set must be at least 1");
        }
        if !(self.lr.is_finite() && self.lr > 0.0) {
            return bad("the learning rate must be positive and finite");
        }
        if !(self.one_shot_weight.is_finite() && self.one_shot_weight >= 0.0) {
            return bad("the one-shot weight must be finite and not negative");
        }
        if !((0.0..=1.0).contains(&self.explore) && (0.0..=1.0).contains(&self.expert_decay)) {
            return bad("explore and expert_decay must lie in [0, 1]");
        }
        Ok(())
    }
}

//! What the training and checkpoint tests share: tiny runs and their exact weights.

use afg_learn::{
    InferBackend,
    nets::{NetworkConfig, QNetwork, parameter_values},
    train::{Algo, TrainConfig},
};

/// A run of `steps` steps at N = 10 with a small batch, buffer and validation set.
pub fn tiny(algo: Algo, net: NetworkConfig, steps: u64) -> TrainConfig {
    let mut c = TrainConfig::new(10, algo, net, steps, 3);
    c.batch = 32;
    c.parallel_envs = 4;
    c.warmup = 64;
    c.replay_capacity = 2_000;
    c.validation_instances = 4;
    c.validate_every = steps / 2;
    c.target_sync = 10;
    c
}

/// Every weight of `net`, bit for bit.
pub fn weight_bits(net: &QNetwork<InferBackend>) -> Vec<u32> {
    parameter_values(net)
        .into_iter()
        .map(f32::to_bits)
        .collect()
}

//! Train a tiny AFGNet with Double DQN for a few hundred steps (N = 10 robots, M = 3
//! tasks) and print the validation curve. About a minute on one core.
//!
//! `cargo run --release -p afg-learn --example train_tiny`

use afg_graph::Units;
use afg_learn::{
    env::Shaping,
    nets::NetworkConfig,
    train::{Algo, TrainConfig, Trainer},
};

fn main() -> Result<(), afg_learn::LearnError> {
    let network = NetworkConfig::afgnet(3, 0).with_units(Units::ScaleFree);
    let mut config = TrainConfig::new(10, Algo::Ddqn, network, 300, 0);
    config.batch = 64;
    config.warmup = 256;
    config.validation_instances = 16;
    config.validate_every = 50;
    config.shaping = Shaping::Greedy;
    let mut trainer = Trainer::new(config)?;
    while !trainer.is_finished() {
        let report = trainer.step()?;
        if let Some(v) = report.validation {
            println!(
                "step {:>4}: validation welfare {:.3} ({:.1} % of OPT)",
                report.step, v.welfare, v.percent_of_opt
            );
        }
    }
    let stem = std::env::temp_dir().join("afg_tiny_model");
    afg_learn::nets::save_network(trainer.network(), &trainer.config().network, &stem)?;
    println!(
        "weights in {}.mpk; load them with LearnedPolicy::load",
        stem.display()
    );
    Ok(())
}

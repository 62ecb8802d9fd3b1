//! Load a committed model and allocate a new instance with it, beside OPT and greedy.
//!
//! `cargo run --release -p afg-learn --example allocate_with_model -- models/paper/afgnet_ddqn_n20 60`
//! (the model directory is relative to the repository root).

use std::path::PathBuf;

use afg_baseline::{Allocator, Greedy, Optimum};
use afg_game::GeneratorConfig;
use afg_learn::{policy::LearnedPolicy, run::RunDir};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let model = args
        .next()
        .unwrap_or_else(|| "models/paper/afgnet_ddqn_n20".into());
    let robots: usize = args.next().map_or(Ok(60), |s| s.parse())?;
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let policy = LearnedPolicy::load(&RunDir::new(root.join(&model)).weights())?;
    let instance = GeneratorConfig::paper(robots, policy.config().tasks(), 7).generate()?;
    let opt = instance.welfare(&Optimum.allocate(&instance)?.assignment);
    for (name, allocator) in [
        (model.as_str(), &policy as &dyn Allocator),
        ("greedy", &Greedy),
        ("opt", &Optimum),
    ] {
        let out = allocator.allocate(&instance)?;
        let welfare = instance.welfare(&out.assignment);
        println!(
            "{name:<28} welfare {welfare:>9.3}  ({:.2} % of OPT)",
            100.0 * welfare / opt
        );
    }
    Ok(())
}

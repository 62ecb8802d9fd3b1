//! A training run's reproducing command and its `manifest.json` (`cargo xtask manifest`).

use std::path::{Path, PathBuf};

use afg_graph::Units;
use afg_learn::{NetworkConfig, Preset, RunDir, Shaping, TrainConfig};
use anyhow::Result;
use clap::Args;

/// The `cargo xtask train` command line that reproduces a configuration.
pub fn command_line(c: &TrainConfig, dir: &Path) -> String {
    let default = TrainConfig::from_preset(
        c.preset,
        c.robots,
        c.algo,
        c.network.clone(),
        c.steps,
        c.seed,
    );
    let mut cmd = format!(
        "cargo xtask train --scale {} --algo {} --net {} --steps {} --seed {}",
        c.robots,
        c.algo.name(),
        c.network.name(),
        c.steps,
        c.seed
    );
    if c.network.tasks() != afg_eval::dataset::TASKS {
        cmd += &format!(" --tasks {}", c.network.tasks());
    }
    if c.batch != default.batch {
        cmd += &format!(" --batch {}", c.batch);
    }
    if c.lr != default.lr {
        cmd += &format!(" --lr {}", c.lr);
    }
    if !c.lr_decay && default.lr_decay {
        cmd += " --constant-lr";
    }
    if c.n_step != default.n_step {
        cmd += &format!(" --n-step {}", c.n_step);
    }
    if c.target_sync != default.target_sync {
        cmd += &format!(" --target-sync {}", c.target_sync);
    }
    if c.parallel_envs != default.parallel_envs {
        cmd += &format!(" --parallel-envs {}", c.parallel_envs);
    }
    if c.validation_instances != default.validation_instances {
        cmd += &format!(" --validation-instances {}", c.validation_instances);
    }
    if c.validate_every != default.validate_every {
        cmd += &format!(" --validate-every {}", c.validate_every);
    }
    let gain_residual =
        matches!(&c.network, NetworkConfig::AfgNet(a) if a.gain_residual == Some(true));
    if c.shaping != default.shaping {
        if c.shaping == Shaping::None {
            if !gain_residual {
                // (--gain-residual implies it)
                cmd += " --no-shaping";
            }
        } else {
            cmd += &format!(" --shaping {}", c.shaping.name());
        }
    }
    if c.network.units() != Units::Bounded {
        cmd += &format!(" --units {}", c.network.units().name());
    }
    if let NetworkConfig::AfgNet(a) = &c.network
        && a.gain_residual == Some(true)
    {
        cmd += " --gain-residual";
    }
    if let NetworkConfig::AfgNet(a) = &c.network
        && a.price_head == Some(true)
    {
        cmd += " --price-head";
    }
    if c.price_loss > 0.0 {
        cmd += &format!(" --price-loss {}", c.price_loss);
    }
    if let Some(d) = &c.demonstrations {
        cmd += &format!(
            " --demos {} --demo-share {} --demo-margin {} --demo-weight {}",
            d.episodes, d.share, d.margin, d.weight
        );
    }
    if c.preset == Preset::Paper {
        cmd += " --paper";
    }
    if c.eps_start != default.eps_start {
        cmd += &format!(" --eps-start {}", c.eps_start);
    }
    if let Some(from) = &c.init_from {
        cmd += &format!(" --init-from {}", from.display());
    }
    cmd + &format!(" --out {}", dir.display())
}

/// Writes `dir/manifest.json` from the run's config and log: the command, seed, steps,
/// wall time, git revision and final validation welfare.
pub fn write_manifest(dir: &Path) -> Result<()> {
    let run = RunDir::new(dir);
    let relative = dir.strip_prefix(crate::repo_root()).unwrap_or(dir);
    let manifest = run.manifest_from_log(command_line(&run.config()?, relative))?;
    run.write_manifest(&manifest)?;
    Ok(())
}

#[derive(Args)]
pub struct ManifestArgs {
    /// Finished run directories.
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
}

/// Rewrites the manifests of finished runs.
pub fn run_manifest(args: ManifestArgs) -> Result<()> {
    for d in &args.dirs {
        write_manifest(d)?;
        println!("wrote {}", d.join("manifest.json").display());
    }
    Ok(())
}

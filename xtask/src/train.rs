//! `cargo xtask train`.

use std::path::PathBuf;
use std::time::Duration;

use afg_eval::dataset;
use afg_graph::Units;
use afg_learn::{
    Algo, Demonstrations, NetworkConfig, Preset, RunDir, Session, Shaping, TrainConfig,
};
use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum AlgoArg {
    /// DQN (the paper's bootstrap rule).
    Dqn,
    /// Double DQN (the paper's).
    Ddqn,
    /// Regression on the exact Q* of every action (ours; not reinforcement learning).
    #[value(name = "qstar")]
    QStar,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum NetArg {
    Afgnet,
    S2v,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum UnitsArg {
    ScaleFree,
    Bounded,
    MeanReward,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ShapingArg {
    /// The paper's reward, the welfare change.
    None,
    /// Potential: the welfare a greedy completion would still add (the default).
    Greedy,
    /// Potential: the welfare the optimal completion would still add (one min-cost flow
    /// per state): the TD targets then carry the exact advantages (ours).
    Optimal,
}

#[derive(Args, Default)]
pub struct TrainArgs {
    /// Robots per training instance N (defaults exist for 20, 60 and 100).
    #[arg(long)]
    pub(crate) scale: Option<usize>,
    /// Tasks per training instance M (the network is built for this M) [default: 5,
    /// the paper's].
    #[arg(long)]
    pub(crate) tasks: Option<usize>,
    /// What the Q values are fitted to (default ddqn).
    #[arg(long, value_enum)]
    pub(crate) algo: Option<AlgoArg>,
    /// Network.
    #[arg(long, value_enum)]
    pub(crate) net: Option<NetArg>,
    /// Gradient steps (default: the per-scale budget of about an hour on 2 cores).
    #[arg(long)]
    pub(crate) steps: Option<u64>,
    /// Seed of everything random in the run (initial weights, instances, exploration).
    #[arg(long)]
    pub(crate) seed: Option<u64>,
    /// Transitions per gradient step.
    #[arg(long)]
    pub(crate) batch: Option<usize>,
    /// Adam learning rate (default 1e-3; the paper's is 1e-4).
    #[arg(long)]
    pub(crate) lr: Option<f64>,
    /// Keep the learning rate constant (by default it anneals linearly to a tenth of
    /// --lr over the run).
    #[arg(long)]
    pub(crate) constant_lr: bool,
    /// n-step returns (1 = the paper's one-step target).
    #[arg(long)]
    pub(crate) n_step: Option<usize>,
    /// Units of the network's inputs and rewards: bounded (the default: scale-free, and
    /// the value part of the task features capped at 4 r_j/eps_j, so that nearly empty
    /// tasks look alike at every N), scale-free (welfare / β, edge weights / their
    /// mean, the same at every N) or mean-reward (welfare / the instance's mean task
    /// reward, raw edge weights: the first models' units).
    #[arg(long, value_enum)]
    pub(crate) units: Option<UnitsArg>,
    /// Gradient steps between target-network syncs (default: the run's budget / 20,
    /// clamped to 10..=1000).
    #[arg(long)]
    pub(crate) target_sync: Option<u64>,
    /// Episodes run side by side (each acting step adds this many transitions).
    #[arg(long)]
    pub(crate) parallel_envs: Option<usize>,
    /// Instances in the fixed validation set (default 32); fewer make each validation
    /// cheaper at large N.
    #[arg(long)]
    pub(crate) validation_instances: Option<usize>,
    /// Gradient steps between validations (default: the run's budget / 40).
    #[arg(long)]
    pub(crate) validate_every: Option<u64>,
    /// Turn off the reward shaping. By default rewards are shaped with the potential
    /// "welfare a greedy completion would still add", so the network learns how much
    /// better than finishing greedily each action is (not in the paper; the optimal
    /// policy is unchanged; docs/training.md).
    #[arg(long)]
    pub(crate) no_shaping: bool,
    /// The shaping potential (default greedy; `--no-shaping` is `--shaping none`).
    #[arg(long, value_enum, conflicts_with = "no_shaping")]
    pub(crate) shaping: Option<ShapingArg>,
    /// AFGNet only: add each action's immediate reward (the actor's join gain) to the
    /// Q values, so the network learns only the value of what follows (not in the paper).
    #[arg(long)]
    pub(crate) gain_residual: bool,
    /// AFGNet only: the price structure Q(s, a) = π_a(s) − β d(t, a) + c_a(s), with a
    /// price head shared by all tasks that reads each task's summaries and the pooled
    /// embedding; the untrained network is Nearest (ours, not in the paper;
    /// docs/price.md).
    #[arg(long)]
    pub(crate) price_head: bool,
    /// Learn from demonstrations as in Deep Q-learning from Demonstrations (ours, not
    /// in the paper): this many expert episodes (each robot on its task in the exact
    /// optimum), a share of every batch drawn from them, and a large-margin loss on the
    /// expert's action. DQN and Double DQN only.
    #[arg(long, value_name = "EPISODES")]
    pub(crate) demos: Option<usize>,
    /// With --demos: share of each batch drawn from the demonstrations.
    #[arg(long, default_value_t = 0.25, requires = "demos")]
    pub(crate) demo_share: f64,
    /// With --demos: the margin by which the expert's action should lead, in the
    /// network's welfare unit (distance units with the default units).
    #[arg(long, default_value_t = 0.05, requires = "demos")]
    pub(crate) demo_margin: f64,
    /// With --demos: weight of the large-margin loss.
    #[arg(long, default_value_t = 1.0, requires = "demos")]
    pub(crate) demo_weight: f64,
    /// With --price-head: weight of the one-shot price loss (ours, not in the paper):
    /// every step also fits the Q values of empty states, plus the actor's distance
    /// cost, to the instance's exact task prices (centred), so that the one-shot mode
    /// (every robot at once on the empty state's Q values) reproduces the optimum.
    #[arg(long, value_name = "WEIGHT", requires = "price_head")]
    pub(crate) price_loss: Option<f64>,
    /// The paper's settings where ours differ: squared loss, raw rewards, no clipping,
    /// target sync every 1000 steps, constant learning rate 1e-4 (an explicit --lr still
    /// wins).
    #[arg(long)]
    pub(crate) paper: bool,
    /// Warm start: begin from the final weights of this run directory (same network and
    /// units) instead of fresh ones, e.g. a model trained at N = 60 for a run at N = 100.
    /// Not in the paper. Usually with a small --eps-start.
    #[arg(long)]
    pub(crate) init_from: Option<PathBuf>,
    /// ε at the start (default 1.0, decaying to 0.05 over the first tenth of the run).
    #[arg(long)]
    pub(crate) eps_start: Option<f64>,
    /// Run directory: config.json, log.jsonl, checkpoint/, and model.{json,mpk} at the end.
    #[arg(long, conflicts_with = "resume")]
    pub(crate) out: Option<PathBuf>,
    /// Continue the run in this directory from its last checkpoint.
    #[arg(long)]
    pub(crate) resume: Option<PathBuf>,
    /// Seconds between checkpoints.
    #[arg(long, default_value_t = 300)]
    pub(crate) checkpoint_secs: u64,
}

impl TrainArgs {
    fn config(&self) -> Result<TrainConfig> {
        let scale = self
            .scale
            .context("--scale is required for a new run (or pass --resume DIR)")?;
        let steps = match self.steps {
            Some(s) => s,
            None => TrainConfig::default_steps(scale).with_context(|| {
                format!("no default budget for --scale {scale} (known: 20, 60, 100); pass --steps")
            })?,
        };
        let seed = self.seed.unwrap_or(0);
        let tasks = self.tasks.unwrap_or(dataset::TASKS);
        let network = match self.net.unwrap_or(NetArg::Afgnet) {
            NetArg::Afgnet => NetworkConfig::AfgNet(
                afg_learn::AfgNetConfig::new(tasks)
                    .with_seed(seed)
                    .with_gain_residual(self.gain_residual.then_some(true))
                    .with_price_head(self.price_head.then_some(true)),
            ),
            NetArg::S2v if self.gain_residual || self.price_head => {
                anyhow::bail!("--gain-residual and --price-head exist for AFGNet only")
            }
            NetArg::S2v => NetworkConfig::s2v(tasks, seed),
        };
        let network = network.with_units(match self.units.unwrap_or(UnitsArg::Bounded) {
            UnitsArg::ScaleFree => Units::ScaleFree,
            UnitsArg::Bounded => Units::Bounded,
            UnitsArg::MeanReward => Units::MeanReward,
        });
        let algo = match self.algo.unwrap_or(AlgoArg::Ddqn) {
            AlgoArg::Dqn => Algo::Dqn,
            AlgoArg::Ddqn => Algo::Ddqn,
            AlgoArg::QStar => Algo::QStar,
        };
        let preset = if self.paper {
            Preset::Paper
        } else {
            Preset::Ours
        };
        let mut c = TrainConfig::from_preset(preset, scale, algo, network, steps, seed);
        if self.constant_lr {
            c.lr_decay = false;
        }
        if let Some(b) = self.batch {
            c.batch = b;
        }
        if let Some(lr) = self.lr {
            c.lr = lr;
        }
        if let Some(k) = self.n_step {
            c.n_step = k;
        }
        if let Some(k) = self.target_sync {
            c.target_sync = k;
        }
        if let Some(k) = self.parallel_envs {
            c.parallel_envs = k;
        }
        if let Some(k) = self.validation_instances {
            c.validation_instances = k;
        }
        if let Some(k) = self.validate_every {
            c.validate_every = k;
        }
        if let Some(e) = self.eps_start {
            c.eps_start = e;
        }
        c.init_from = self.init_from.clone();
        if let Some(w) = self.price_loss {
            c.price_loss = w;
        }
        c.demonstrations = self.demos.map(|episodes| Demonstrations {
            episodes,
            share: self.demo_share,
            margin: self.demo_margin,
            weight: self.demo_weight,
        });
        // The gain residual adds the unshaped reward to Q: it implies no shaping.
        if let Some(shaping) = self.shaping {
            c.shaping = match shaping {
                ShapingArg::None => Shaping::None,
                ShapingArg::Greedy => Shaping::Greedy,
                ShapingArg::Optimal => Shaping::Optimal,
            };
        }
        if self.no_shaping || self.gain_residual {
            c.shaping = Shaping::None;
        }
        c.check()?;
        Ok(c)
    }

    fn any_setting_given(&self) -> bool {
        self.scale.is_some()
            || self.tasks.is_some()
            || self.algo.is_some()
            || self.net.is_some()
            || self.steps.is_some()
            || self.seed.is_some()
            || self.batch.is_some()
            || self.lr.is_some()
            || self.constant_lr
            || self.n_step.is_some()
            || self.units.is_some()
            || self.target_sync.is_some()
            || self.parallel_envs.is_some()
            || self.no_shaping
            || self.shaping.is_some()
            || self.gain_residual
            || self.price_head
            || self.demos.is_some()
            || self.paper
            || self.init_from.is_some()
            || self.eps_start.is_some()
    }
}

pub fn run(args: TrainArgs) -> Result<()> {
    let mut session = match &args.resume {
        Some(dir) => {
            if args.any_setting_given() && args.config()? != RunDir::new(dir).config()? {
                bail!(
                    "{} holds a run with other settings; resume it without settings, or start a new run with --out",
                    dir.display()
                );
            }
            let session =
                Session::resume(dir).with_context(|| format!("resuming {}", dir.display()))?;
            let step = session.trainer().steps_done();
            eprintln!("resuming {} at step {step}", dir.display());
            session
        }
        None => {
            let config = args.config()?;
            let dir = args
                .out
                .as_ref()
                .context("pass --out DIR for a new run (or --resume DIR)")?;
            Session::start(dir, config, git_revision())?
        }
    };
    let config = session.trainer().config().clone();
    let name = format!(
        "{}_{} N={}",
        config.network.name(),
        config.algo.name(),
        config.robots
    );
    let bar = crate::progress(config.steps, &name);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg} [{bar:25}] {pos}/{len} {per_sec} eta {eta}")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar.set_position(session.trainer().steps_done());
    let mut last_val = f64::NAN;
    let every = Duration::from_secs(args.checkpoint_secs);
    let v = session.run(every, |report| {
        let (step, loss, epsilon) = (report.step, report.loss, report.epsilon);
        if let Some(result) = &report.validation {
            last_val = result.welfare;
            if result.collapsed() {
                bar.suspend(|| {
                    eprintln!(
                        "warning: step {step}: collapse — on average {:.0} % of the robots took one task",
                        100.0 * result.largest_task_share
                    )
                });
            }
        }
        bar.set_position(step);
        bar.set_message(format!(
            "{name} ε {epsilon:.2} loss {loss:.4} val {last_val:.2}"
        ));
    })?;
    bar.finish_and_clear();
    println!(
        "{name}: {} steps; validation welfare {:.3} ({:.2} % of OPT); model in {}",
        session.trainer().steps_done(),
        v.welfare,
        v.percent_of_opt,
        session.run_dir().weights().display()
    );
    Ok(())
}

/// The checked-out git revision, if there is one.
fn git_revision() -> Option<String> {
    std::process::Command::new("git")
        .args(["rev-parse", "HEAD"])
        .current_dir(crate::repo_root())
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_owned())
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    use super::*;
    use std::path::Path;

    fn xtask(args: &[&str]) -> Result<()> {
        let mut argv = vec!["cargo xtask"];
        argv.extend_from_slice(args);
        match crate::Cli::try_parse_from(argv)?.command {
            crate::Command::Train(a) => run(a),
            crate::Command::PlotCurves(a) => crate::curves::run_plot(a),
            _ => unreachable!("only train and plot-curves here"),
        }
    }

    #[test]
    fn command_line_reproduces_the_configuration() {
        let dir = Path::new("models/x");
        for flags in [
            "--scale 20",
            "--scale 60 --algo dqn --net s2v --steps 50 --seed 3",
            "--scale 20 --lr 0.001 --batch 64 --n-step 3",
            "--scale 20 --gain-residual",
            "--scale 100 --paper",
            "--scale 20 --constant-lr --lr 0.01",
            "--scale 60 --units mean-reward --target-sync 77 --parallel-envs 8",
            "--scale 60 --units bounded",
            "--scale 20 --paper --target-sync 50",
            "--scale 60 --no-shaping",
            "--scale 60 --shaping optimal",
            "--scale 20 --paper --shaping greedy",
            "--scale 100 --init-from models/afgnet_ddqn_n60 --eps-start 0.1",
            "--scale 60 --price-head --algo qstar",
            "--scale 60 --tasks 50 --price-head --algo qstar",
            "--scale 60 --price-head --algo qstar --price-loss 0.5",
            "--scale 600 --tasks 50 --steps 100 --validation-instances 8 --validate-every 50",
            "--scale 60 --price-head --demos 64 --demo-margin 0.1 --demo-share 0.5",
        ] {
            let argv = ["cargo xtask", "train"]
                .into_iter()
                .chain(flags.split(' '))
                .chain(["--out", "models/x"]);
            let crate::Command::Train(args) = crate::Cli::try_parse_from(argv).unwrap().command
            else {
                unreachable!("a train command")
            };
            let config = args.config().unwrap();
            let line = crate::manifest::command_line(&config, dir);
            let crate::Command::Train(again) = crate::Cli::try_parse_from(line.split(' ').skip(1))
                .unwrap()
                .command
            else {
                unreachable!("a train command")
            };
            assert_eq!(
                serde_json::to_value(again.config().unwrap()).unwrap(),
                serde_json::to_value(&config).unwrap(),
                "{line}"
            );
            assert!(line.ends_with(" --out models/x"), "{line}");
        }
    }

    #[test]
    fn train_writes_log_checkpoint_model_and_a_plottable_curve() {
        let dir = std::env::temp_dir().join(format!("afg-xtask-train-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let run_dir = dir.join("run");
        let out = run_dir.to_str().unwrap();
        xtask(&[
            "train", "--scale", "10", "--steps", "120", "--batch", "32", "--net", "s2v", "--out",
            out,
        ])
        .unwrap();
        // What the run directory holds is tested in afg-learn (Session).
        afg_learn::LearnedPolicy::load(&run_dir.join("model")).unwrap();
        assert!(run_dir.join("checkpoint/state.json").exists());

        let svg = dir.join("curves.svg");
        xtask(&["plot-curves", out, "--out", svg.to_str().unwrap()]).unwrap();
        let text = std::fs::read_to_string(&svg).unwrap();
        assert!(text.starts_with("<svg") && text.trim_end().ends_with("</svg>"));
        assert!(text.contains("run (s2v_ddqn, N = 10)"));

        // A second run into the same directory is refused; nothing is overwritten.
        let before = std::fs::read(run_dir.join("model.mpk")).unwrap();
        let err = xtask(&["train", "--scale", "10", "--steps", "5", "--out", out]).unwrap_err();
        assert!(
            err.to_string().contains("already holds a training run"),
            "{err}"
        );
        // Resuming with other settings is refused too.
        let err = xtask(&["train", "--resume", out, "--scale", "20", "--steps", "5"]).unwrap_err();
        assert!(err.to_string().contains("other settings"), "{err}");
        assert_eq!(std::fs::read(run_dir.join("model.mpk")).unwrap(), before);
        // Unknown values are refused by the parser.
        assert!(xtask(&["train", "--scale", "20", "--net", "gcn", "--out", out]).is_err());
        assert!(xtask(&["train", "--scale", "20", "--algo", "ppo", "--out", out]).is_err());
        let err = xtask(&[
            "train",
            "--scale",
            "33",
            "--out",
            dir.join("x").to_str().unwrap(),
        ])
        .unwrap_err();
        assert!(err.to_string().contains("no default budget"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

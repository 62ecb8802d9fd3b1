//! `cargo xtask crash-test`: SIGKILLs `afg train` and `afg train-price` at random moments
//! and resumes them each time; the final weights must equal an uninterrupted run's.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use afg_learn::{
    InferBackend,
    nets::{load_network, parameter_values},
    price::PriceModel,
    run::RunDir,
};
use anyhow::{Context, Result, bail, ensure};
use clap::Args;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The options of `cargo xtask crash-test`.
#[derive(Args)]
pub struct CrashArgs {
    /// Kills per trainer (each at a random moment of a run, then a resume).
    #[arg(long, default_value_t = 20)]
    kills: usize,
    /// Seed of the kill moments.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Scratch directory for the runs: new, or one an earlier crash test wrote (its run
    /// directories are replaced; a directory holding anything else is refused).
    #[arg(long, default_value = "target/crash-test")]
    dir: PathBuf,
}

/// A trainer under test: how to start it, how to continue it, how to compare its weights.
struct Target {
    name: &'static str,
    /// The command and the arguments of a new run, without `--out DIR`.
    start: &'static [&'static str],
    /// Arguments of every run, new or resumed.
    always: &'static [&'static str],
    /// Whether a killed run continues with `--resume DIR`; otherwise (train-price, which
    /// keeps no checkpoints) the same command starts it again.
    resumes: bool,
    /// Whether a run directory holds the final weights (written last, atomically).
    finished: fn(&Path) -> bool,
    /// Whether two run directories hold the same final weights.
    same_weights: fn(&Path, &Path) -> Result<bool>,
}

/// A small `train` run that checkpoints after every step, so that kills can land in a
/// checkpoint write, and a small `train-price` run.
const TARGETS: [Target; 2] = [
    Target {
        name: "train",
        start: &[
            "train",
            "--scale",
            "20",
            "--steps",
            "150",
            "--batch",
            "16",
            "--validation-instances",
            "2",
            "--validate-every",
            "50",
        ],
        always: &["--checkpoint-secs", "0"],
        resumes: true,
        finished: |dir| RunDir::new(dir).has_weights(),
        same_weights: same_network,
    },
    Target {
        name: "train-price",
        start: &[
            "train-price",
            "--scale",
            "12",
            "--tasks",
            "3",
            "--rounds",
            "30",
            "--episodes",
            "4",
            "--steps",
            "10",
        ],
        always: &[],
        resumes: false,
        finished: |dir| dir.join(PriceModel::FILE_NAME).exists(),
        same_weights: same_price_model,
    },
];

/// What happened to one trainer.
#[derive(Default)]
struct Outcome {
    kills: usize,
    /// Kills that left a checkpoint half written (`checkpoint.new` present, or the
    /// current checkpoint renamed away and the new one not yet in its place).
    in_checkpoint_write: usize,
    resumes: usize,
    /// Runs started anew after a kill: train-price always; train when killed before
    /// its config was written (the directory holds no run and `--resume` says so).
    restarts: usize,
    /// Runs that reached their end, each compared with the uninterrupted run.
    completed: usize,
    reference_s: f64,
    equal: bool,
}

/// Runs `cargo xtask crash-test`.
pub fn run(args: CrashArgs) -> Result<()> {
    let exe = std::env::current_exe().context("the xtask binary")?;
    clear_scratch(&args.dir)?;
    let mut rng = ChaCha8Rng::seed_from_u64(args.seed);
    println!(
        "| trainer | kills | in a checkpoint write | resumes | restarts | runs completed | uninterrupted run | final weights equal |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    let mut failed = Vec::new();
    for trainer in &TARGETS {
        let o = crash_trainer(&exe, trainer, &args.dir, args.kills, &mut rng)?;
        println!(
            "| {} | {} | {} | {} | {} | {} | {:.1} s | {} |",
            trainer.name,
            o.kills,
            o.in_checkpoint_write,
            o.resumes,
            o.restarts,
            o.completed,
            o.reference_s,
            if o.equal { "yes" } else { "**no**" }
        );
        if !o.equal {
            failed.push(trainer.name);
        }
    }
    ensure!(
        failed.is_empty(),
        "final weights differ: {}",
        failed.join(", ")
    );
    Ok(())
}

/// Makes `dir` ready for the runs: an earlier crash test's run directories are
/// removed, anything else there is an error (nothing of the user's is deleted).
fn clear_scratch(dir: &Path) -> Result<()> {
    let ours: Vec<String> = TARGETS
        .iter()
        .flat_map(|t| [t.name.to_owned(), format!("{}-killed", t.name)])
        .collect();
    if !dir.exists() {
        return Ok(());
    }
    for entry in std::fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))? {
        let name = entry?.file_name();
        if !ours.iter().any(|o| name == o.as_str()) {
            bail!(
                "{} holds {} which no crash test wrote; pass a new or empty --dir",
                dir.display(),
                name.to_string_lossy()
            );
        }
    }
    for name in &ours {
        let path = dir.join(name);
        if path.exists() {
            std::fs::remove_dir_all(&path)?;
        }
    }
    Ok(())
}

/// Runs `trainer` once uninterrupted, then in a second directory kills it `kills`
/// times, each at a random moment of a run, and continues it after each kill. A run
/// that ends before its kill is compared with the uninterrupted one and started anew,
/// so that the kills spread over the whole run; the last one is let end and compared.
fn crash_trainer(
    exe: &Path,
    trainer: &Target,
    root: &Path,
    kills: usize,
    rng: &mut ChaCha8Rng,
) -> Result<Outcome> {
    let reference = root.join(trainer.name);
    let crashed = root.join(format!("{}-killed", trainer.name));
    let start = Instant::now();
    finish(spawn(exe, trainer, &reference, false)?, trainer.name)?;
    let mut o = Outcome {
        reference_s: start.elapsed().as_secs_f64(),
        equal: true,
        ..Outcome::default()
    };
    // A resumed run goes on from its checkpoint, so kills within the first half of
    // each resumed run reach its end after a few kills.
    let span = o.reference_s * if trainer.resumes { 0.5 } else { 0.9 };
    let bar = afg_eval::report::progress(kills as u64, &format!("crash-test {}", trainer.name));
    let compare = |o: &mut Outcome| -> Result<()> {
        o.completed += 1;
        o.equal &= (trainer.same_weights)(&reference, &crashed)?;
        std::fs::remove_dir_all(&crashed)?;
        Ok(())
    };
    loop {
        let resume = trainer.resumes && crashed.join("config.json").exists();
        if crashed.exists() {
            o.resumes += usize::from(resume);
            o.restarts += usize::from(!resume);
        }
        let mut child = spawn(exe, trainer, &crashed, resume)?;
        if o.kills == kills {
            finish(child, trainer.name)?;
            compare(&mut o)?;
            break;
        }
        let delay = Duration::from_secs_f64(rng.random_range(0.0..span));
        if trainer.resumes && o.kills % 2 == 1 {
            // Every second kill is aimed at a checkpoint write: it lands as soon as a
            // new checkpoint directory appears (or at the random moment otherwise).
            wait_for(&crashed.join("checkpoint.new"), &mut child, delay)?;
        } else {
            std::thread::sleep(delay);
        }
        if let Some(status) = child.try_wait()? {
            // It ended before the kill, and must have succeeded.
            check(status, child, trainer.name)?;
            compare(&mut o)?;
            continue;
        }
        child.kill()?; // SIGKILL
        child.wait()?;
        o.kills += 1;
        bar.inc(1);
        let (fresh, current) = (crashed.join("checkpoint.new"), crashed.join("checkpoint"));
        let old = crashed.join("checkpoint.old");
        o.in_checkpoint_write += usize::from(fresh.exists() || (old.exists() && !current.exists()));
        if (trainer.finished)(&crashed) {
            // Killed after its final weights were written: the run is complete.
            compare(&mut o)?;
        }
    }
    bar.finish_and_clear();
    Ok(o)
}

/// Whether two `train` runs ended with the same network: equal headers and
/// bit-equal parameters (the records differ in Burn's random parameter ids).
fn same_network(a: &Path, b: &Path) -> Result<bool> {
    let load = |dir: &Path| -> Result<(Vec<u8>, Vec<u32>)> {
        let run = RunDir::new(dir);
        let header = std::fs::read(dir.join(RunDir::WEIGHT_FILES[0]))?;
        let (_, net) = load_network::<InferBackend>(&run.weights(), &Default::default())?;
        Ok((
            header,
            parameter_values(&net)
                .into_iter()
                .map(f32::to_bits)
                .collect(),
        ))
    };
    Ok(load(a)? == load(b)?)
}

/// Whether two `train-price` runs wrote the same model file (it holds the weights as
/// numbers, with no ids).
fn same_price_model(a: &Path, b: &Path) -> Result<bool> {
    let read = |dir: &Path| std::fs::read(dir.join(PriceModel::FILE_NAME));
    Ok(read(a)? == read(b)?)
}

/// Waits until `path` exists, `child` ends or `limit` has passed.
fn wait_for(path: &Path, child: &mut Child, limit: Duration) -> Result<()> {
    let start = Instant::now();
    while !path.exists() && child.try_wait()?.is_none() && start.elapsed() < limit {
        std::thread::sleep(Duration::from_micros(200));
    }
    Ok(())
}

/// Starts a run of `trainer` in `dir`: new, or continued with `--resume`.
fn spawn(exe: &Path, trainer: &Target, dir: &Path, resume: bool) -> Result<Child> {
    // `xtask afg …` runs the afg command in this binary.
    let mut command = Command::new(exe);
    command.arg("afg");
    if resume {
        command.args([trainer.start[0], "--resume"]);
    } else {
        command.args(trainer.start).arg("--out");
    }
    command.arg(dir).args(trainer.always);
    Ok(command
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()?)
}

fn finish(child: Child, name: &str) -> Result<()> {
    let mut child = child;
    let status = child.wait()?;
    check(status, child, name)
}

/// A run that ended by itself must have succeeded; its error is shown if not.
fn check(status: std::process::ExitStatus, child: Child, name: &str) -> Result<()> {
    if !status.success() {
        let output = child.wait_with_output()?;
        bail!(
            "{name} failed after a kill ({status}): {}",
            String::from_utf8_lossy(&output.stderr).trim()
        );
    }
    Ok(())
}

//! `cargo xtask study-families`: staffing models (ours) trained on one named family, on
//! a mixture of families and on every family of the mixture but one, each tested on
//! held-out games of every family against the exact solver's optimum — the in-family
//! and leave-one-family-out table of docs/families.md.
//!
//! Each family's games are labelled once, by the model trained on it alone; the
//! mixtures read those labels back (a family's games are the same in every run that
//! names it), so a mixture costs only its fitting.

use std::path::{Path, PathBuf};

use afg_baseline::{Allocator, TeamOptimum};
use afg_game::{Family, GameSize, Instance};
use afg_learn::price::PriceNetConfig;
use afg_learn::run::{ModelOptions, load_model};
use afg_learn::staffing::{
    LABELS_FILE_NAME, StaffingModel, StaffingPolicy, StaffingTrainConfig, StaffingTrainer,
};
use anyhow::{Context, Result};
use clap::Args;
use rayon::prelude::*;
use serde::Serialize;

/// The options of `cargo xtask study-families`.
#[derive(Args)]
pub struct StudyFamiliesArgs {
    /// Where the models are (one run directory per training set); a model already there
    /// is tested as it is, a missing one is trained.
    #[arg(long, default_value = "models/ours/families")]
    out: PathBuf,
    /// Training games per family (100 robots × 20 tasks, the size of the tests).
    #[arg(long, default_value_t = 200)]
    games: usize,
    /// Validation games per family.
    #[arg(long, default_value_t = 5)]
    validation_games: usize,
    /// The exact solver's time limit per training game, seconds.
    #[arg(long, default_value_t = 2.0)]
    label_time_limit: f64,
    /// Passes over the labelled games.
    #[arg(long, default_value_t = 40)]
    epochs: usize,
    /// Test games per family (seeds from --seed; training draws seeds from 2^62 and
    /// validation from 2^63, so these are held out).
    #[arg(long, default_value_t = 10)]
    instances: usize,
    /// Seed of the first test game.
    #[arg(long, default_value_t = 54)]
    seed: u64,
    /// The reference's time limit per test game, seconds: the exact solver's proven
    /// optimum, or its bound where it stops.
    #[arg(long, default_value_t = 5.0)]
    time_limit: f64,
    /// Print one JSON line per family instead of the Markdown table.
    #[arg(long)]
    json: bool,
}

/// The groups of families, by the committed model whose name their runs extend
/// (models/README.md): the threshold games, and the games with skills.
const GROUPS: [(&str, bool); 2] = [("staffing_teams", false), ("staffing_skills", true)];

/// The families of a group: those that draw skills, or those that do not.
fn families_of(skills: bool) -> Vec<Family> {
    (Family::ALL.into_iter())
        .filter(|f| f.draws_skills() == skills)
        .collect()
}

/// The training and test games' size.
const SIZE: GameSize = GameSize {
    robots: 100,
    tasks: 20,
};

/// One method's share of the reference on a family's test games.
#[derive(Serialize)]
struct Share {
    mean: f64,
    worst: f64,
}

/// One family's row.
#[derive(Serialize)]
struct Row {
    family: Family,
    /// The pipeline with no network.
    hand_written: Share,
    /// The committed model trained on `scarce` (thresholds) or `skills`.
    committed: Share,
    /// Trained on this family alone.
    this_family: Share,
    /// Trained on every family of its group.
    all: Share,
    /// Trained on every family of its group but this one.
    left_out: Share,
    /// The committed model with its repair (the welfare climb after the placement).
    committed_repaired: Share,
    /// Trained without this family, with its repair.
    left_out_repaired: Share,
}

/// Trains (where missing) and tests every model; prints the table.
pub fn run(args: StudyFamiliesArgs) -> Result<()> {
    let mut rows = Vec::new();
    for (group, skills) in GROUPS {
        let families = &families_of(skills)[..];
        for &family in families {
            train(
                &args,
                group,
                &run_dir(&args.out, group, "on", family),
                &[family],
            )?;
        }
        let mixture = args.out.join(format!("{group}_mixture"));
        train(&args, group, &mixture, families)?;
        for &family in families {
            let rest: Vec<Family> = families.iter().copied().filter(|&f| f != family).collect();
            train(
                &args,
                group,
                &run_dir(&args.out, group, "without", family),
                &rest,
            )?;
        }
        for &family in families {
            let row = test(&args, group, family)?;
            if args.json {
                println!("{}", serde_json::to_string(&row)?);
            }
            rows.push(row);
        }
    }
    if !args.json {
        print!("{}", table(&args, &rows));
    }
    Ok(())
}

/// The run of `group` trained `on` one family alone or `without` it.
fn run_dir(out: &Path, group: &str, how: &str, family: Family) -> PathBuf {
    out.join(format!("{group}_{how}-{family}"))
}

/// Trains `group`'s model of `families` into `dir` unless one is there, starting from
/// the labels of each family's own run.
fn train(args: &StudyFamiliesArgs, group: &str, dir: &Path, families: &[Family]) -> Result<()> {
    if dir.join(StaffingModel::FILE_NAME).exists() {
        return Ok(());
    }
    let labels = dir.join(LABELS_FILE_NAME);
    if families.len() > 1 && !labels.exists() {
        let mut text = String::new();
        for family in families {
            let own = run_dir(&args.out, group, "on", *family).join(LABELS_FILE_NAME);
            text += &std::fs::read_to_string(&own)
                .with_context(|| format!("reading {}", own.display()))?;
        }
        std::fs::create_dir_all(dir)?;
        afg_game::fs::write_atomic(&labels, text.as_bytes())?;
    }
    let mut config = StaffingTrainConfig::new(0);
    config.sizes = vec![SIZE];
    config.families = families.to_vec();
    (config.games, config.validation_games) = (args.games, args.validation_games);
    (config.label_time_limit, config.epochs) = (args.label_time_limit, args.epochs);
    let names: Vec<&str> = families.iter().map(|f| f.name()).collect();
    let command = format!(
        "afg train-staffing --families {} --sizes {}x{} --games {} --validation-games {} --label-time-limit {} --epochs {} --out {}",
        names.join(","),
        SIZE.robots,
        SIZE.tasks,
        args.games,
        args.validation_games,
        args.label_time_limit,
        args.epochs,
        dir.display()
    );
    eprintln!("{command}");
    let bar = afg_eval::report::progress(config.training_game_count() as u64, "label games");
    let last = std::cell::Cell::new(0.0);
    StaffingTrainer::new(config)?.run_in(
        dir,
        command,
        |_| bar.inc(1),
        |e| last.set(e.percent_of_opt),
    )?;
    bar.finish_and_clear();
    eprintln!("  validation {:.2} % of OPT", last.get());
    Ok(())
}

/// Every model's share of the reference on `family`'s test games.
fn test(args: &StudyFamiliesArgs, group: &str, family: Family) -> Result<Row> {
    let games: Vec<(Instance, f64)> = (0..args.instances as u64)
        .into_par_iter()
        .map(|k| {
            let inst = family
                .config(SIZE.robots, SIZE.tasks, args.seed + k)?
                .generate()?;
            let best = TeamOptimum::with_time_limit(args.time_limit)?.solve(&inst)?;
            Ok((
                inst,
                if best.proven {
                    best.welfare
                } else {
                    best.bound
                },
            ))
        })
        .collect::<Result<_>>()?;
    let share = |allocator: &dyn Allocator| -> Result<Share> {
        let mut shares = Vec::new();
        for (inst, reference) in &games {
            let out = allocator.allocate(inst)?.assignment;
            inst.check(&out)?;
            shares.push(100.0 * inst.welfare(&out) / reference);
        }
        Ok(Share {
            mean: shares.iter().sum::<f64>() / shares.len() as f64,
            worst: shares.iter().copied().fold(f64::INFINITY, f64::min),
        })
    };
    let model = |dir: PathBuf, repair: bool| -> Result<Share> {
        let options = ModelOptions {
            repair,
            ..ModelOptions::default()
        };
        let policy =
            load_model(&dir, options).with_context(|| format!("loading {}", dir.display()))?;
        share(policy.as_ref())
    };
    let hand =
        StaffingPolicy::untrained(PriceNetConfig { hidden: 1, seed: 0 }, family.draws_skills());
    Ok(Row {
        family,
        hand_written: share(&hand)?,
        committed: model(Path::new("models/ours").join(group), false)?,
        this_family: model(run_dir(&args.out, group, "on", family), false)?,
        all: model(args.out.join(format!("{group}_mixture")), false)?,
        left_out: model(run_dir(&args.out, group, "without", family), false)?,
        committed_repaired: model(Path::new("models/ours").join(group), true)?,
        left_out_repaired: model(run_dir(&args.out, group, "without", family), true)?,
    })
}

/// The Markdown table.
fn table(args: &StudyFamiliesArgs, rows: &[Row]) -> String {
    let cell = |s: &Share| format!("{:.2} / {:.2}", s.mean, s.worst);
    let mut out = format!(
        "Staffing models (ours) on {} held-out games per family ({}×{}, seeds {}–{}), % of the exact solver's optimum (its bound where it stops at {} s): mean / worst game. \
         Each trained on {} games per family, labelled at {} s, {} epochs; repaired: the welfare climb (robot moves, swaps, whole teams dissolved or staffed) after the placement, `--repair`:\n\n",
        args.instances,
        SIZE.robots,
        SIZE.tasks,
        args.seed,
        args.seed + args.instances as u64 - 1,
        args.time_limit,
        args.games,
        args.label_time_limit,
        args.epochs
    );
    out += "| family | hand-written knapsack | committed model (scarce or skills only) | trained on this family | trained on its whole group | trained on its group without it | committed model, repaired (ours) | trained without it, repaired (ours) |\n|---|---|---|---|---|---|---|---|\n";
    for r in rows {
        out += &format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} |\n",
            r.family,
            cell(&r.hand_written),
            cell(&r.committed),
            cell(&r.this_family),
            cell(&r.all),
            cell(&r.left_out),
            cell(&r.committed_repaired),
            cell(&r.left_out_repaired)
        );
    }
    let mut runs = Vec::new();
    for (group, skills) in GROUPS {
        let families = families_of(skills);
        runs.extend(families.iter().map(|f| format!("`{group}_on-{f}`")));
        runs.push(format!("`{group}_mixture`"));
        runs.extend(families.iter().map(|f| format!("`{group}_without-{f}`")));
    }
    out += &format!(
        "\nThe committed models are `staffing_teams` and `staffing_skills`; the others, in `{}`: {}.\n",
        args.out.display(),
        runs.join(", ")
    );
    out
}

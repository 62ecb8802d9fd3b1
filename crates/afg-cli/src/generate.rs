//! `afg gen`: your own instances from the paper's distribution, every knob exposed.

use std::path::PathBuf;

use afg_game::fs::write_atomic;
use afg_game::io::dataset_to_jsonl;
use afg_game::{Family, GeneratorConfig, GeneratorKnobs, Instance};
use anyhow::{Result, bail};
use clap::Args;

/// `afg gen`: the generator's knobs and the output file.
#[derive(Args)]
pub struct GenArgs {
    /// Robots N per instance.
    #[arg(long)]
    robots: usize,
    /// Tasks M per instance.
    #[arg(long, default_value_t = GeneratorConfig::PAPER_TASKS)]
    tasks: usize,
    /// Number of instances.
    #[arg(long, default_value_t = 1)]
    count: usize,
    /// Seed of instance 0; instance i uses seed + i.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Draw capacities from ⌈N/M⌉ ..= ⌈s·N/M⌉ (s ≥ 1; default: no capacities).
    #[arg(long)]
    capacity_slack: Option<f64>,
    /// The base eps of every task's log (default max(2, N/M); at least φ ≈ 1.618).
    #[arg(long)]
    eps: Option<f64>,
    /// Distance penalty β (default 1).
    #[arg(long)]
    beta: Option<f64>,
    /// Initial rewards uniform in [LO, HI] (default [N/M, 2N/M]), e.g. `--rewards 12,24`.
    #[arg(long, value_delimiter = ',', num_args = 1, value_names = ["LO,HI"])]
    rewards: Option<Vec<f64>>,
    /// Instances of GRAPE's game: a robot may join the void task (no coalition,
    /// utility 0) instead of a task, e.g. when every task would cost it more than it
    /// brings ("allow_void": true in each instance).
    #[arg(long)]
    allow_void: bool,
    #[command(flatten)]
    teams: TeamArgs,
    /// Start from a named family of team games instead of the paper's game (the knobs
    /// given beside it override its values): scarce, skills (the committed ones),
    /// clustered, heavy-tail, constant, team-rewards, sparse-skills, many-skills,
    /// void-capacity, mixed. docs/families.md says what each draws.
    #[arg(long, value_name = "NAME", value_parser = str::parse::<Family>)]
    family: Option<Family>,
    /// Output JSON Lines file (one instance per line, generator parameters inside).
    #[arg(long)]
    out: PathBuf,
}

/// The instances `afg gen` makes: the paper's distribution with every knob.
pub fn generate(args: &GenArgs) -> Result<Vec<Instance>> {
    if args.count == 0 {
        bail!("--count must be at least 1");
    }
    let knobs = GeneratorKnobs {
        capacity_slack: args.capacity_slack,
        eps: args.eps,
        beta: args.beta,
        rewards: pair("--rewards", args.rewards.as_deref())?,
        allow_void: args.allow_void,
        min_team: args.teams.min_team()?,
        skills: args.teams.skills,
        skill_share: args.teams.skill_share,
        requires: args.teams.requires()?,
        family: args.family,
    };
    (0..args.count as u64)
        .map(|i| {
            let seed = args.seed.wrapping_add(i);
            Ok(knobs.config(args.robots, args.tasks, seed)?.generate()?)
        })
        .collect()
}

/// The team game's knobs, as `afg gen` and `afg mission gen` take them.
#[derive(Args)]
pub struct TeamArgs {
    /// Team thresholds: each task earns nothing (does no work, in a mission) until its
    /// coalition has at least `min_team` robots, drawn uniformly from LO..=HI (default:
    /// 1, the paper's game), e.g. `--min-team 1,5`.
    #[arg(long, value_delimiter = ',', num_args = 1, value_names = ["LO,HI"])]
    min_team: Option<Vec<usize>>,
    /// Skills: S skills, each robot holding each one with probability --skill-share;
    /// a task earns nothing until its coalition holds what it requires of each
    /// (default: no skills).
    #[arg(long, value_name = "S")]
    pub skills: Option<usize>,
    /// The probability that a robot holds a skill (with --skills; default 0.5).
    #[arg(long, value_name = "P")]
    pub skill_share: Option<f64>,
    /// Each task requires each skill in an amount drawn uniformly from LO..=HI (with
    /// --skills; default 1,2).
    #[arg(long, value_delimiter = ',', num_args = 1, value_names = ["LO,HI"])]
    requires: Option<Vec<usize>>,
}

impl TeamArgs {
    /// `--min-team LO,HI`.
    pub fn min_team(&self) -> Result<Option<(usize, usize)>> {
        pair("--min-team", self.min_team.as_deref())
    }

    /// `--requires LO,HI`.
    pub fn requires(&self) -> Result<Option<(usize, usize)>> {
        pair("--requires", self.requires.as_deref())
    }
}

/// A `LO,HI` flag's two values.
pub(crate) fn pair<T: Copy>(flag: &str, values: Option<&[T]>) -> Result<Option<(T, T)>> {
    match values {
        None => Ok(None),
        Some(&[lo, hi]) => Ok(Some((lo, hi))),
        Some(_) => bail!("{flag} takes two numbers, LO,HI"),
    }
}

/// Draws the instances and writes them, atomically; names the tasks no team can staff.
///
/// # Errors
/// A knob out of range, or the file not written.
pub fn run(args: GenArgs) -> Result<()> {
    let instances = generate(&args)?;
    crate::warn_unstaffable(&instances);
    let text = dataset_to_jsonl(&instances);
    write_atomic(&args.out, text.as_bytes())?;
    println!(
        "wrote {} ({} instance{}, N = {}, M = {}, {:.1} MB)",
        args.out.display(),
        instances.len(),
        if instances.len() == 1 { "" } else { "s" },
        args.robots,
        args.tasks,
        text.len() as f64 / 1e6
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gen_args(flags: &str) -> GenArgs {
        let Ok(crate::Command::Gen(args)) = crate::parse(&format!("gen {flags}")) else {
            unreachable!("a gen command")
        };
        args
    }

    #[test]
    fn custom_instances_follow_every_knob_and_the_seed() {
        let args = gen_args(
            "--robots 30 --tasks 4 --count 3 --seed 9 --capacity-slack 1.2 --eps 3 --beta 0.5 --rewards 2,5 --out x.jsonl",
        );
        let a = generate(&args).unwrap();
        assert_eq!(a.len(), 3);
        for inst in &a {
            assert_eq!(
                (inst.num_robots(), inst.num_tasks(), inst.beta()),
                (30, 4, 0.5)
            );
            assert!(
                inst.tasks()
                    .iter()
                    .all(|t| t.eps == 3.0 && t.capacity.is_some())
            );
            assert!(inst.tasks().iter().all(|t| (2.0..=5.0).contains(&t.reward)));
        }
        // The same seed gives the same instances; instance i is seed + i.
        assert_eq!(generate(&args).unwrap(), a);
        let one = generate(&gen_args(
            "--robots 30 --tasks 4 --seed 10 --capacity-slack 1.2 --eps 3 --beta 0.5 --rewards 2,5 --out x.jsonl",
        ))
        .unwrap();
        assert_eq!(one[0], a[1]);
    }

    #[test]
    fn team_knobs_draw_thresholds_and_skills_in_their_ranges() {
        let args = gen_args(
            "--robots 40 --tasks 6 --seed 3 --min-team 2,5 --skills 3 --skill-share 0.25 --requires 0,2 --out x.jsonl",
        );
        let inst = &generate(&args).unwrap()[0];
        assert!(inst.has_teams() && inst.num_skills() == 3);
        assert!(inst.task_ids().all(|j| (2..=5).contains(&inst.min_team(j))));
        assert!(
            inst.task_ids()
                .all(|j| inst.requires(j).iter().all(|&r| r <= 2))
        );
        let held: u32 = inst.robot_ids().flat_map(|i| inst.skills(i).to_vec()).sum();
        assert!(
            inst.robot_ids()
                .all(|i| inst.skills(i).iter().all(|&q| q <= 1))
        );
        // About a quarter of the 120 robot-skill pairs (the seed makes it exact).
        assert!((15..=45).contains(&held), "{held}");
        // Without the team knobs the same seed draws the same game as before.
        let plain =
            &generate(&gen_args("--robots 40 --tasks 6 --seed 3 --out x.jsonl")).unwrap()[0];
        assert_eq!(plain.robots(), inst.robots());
        assert_eq!(plain.tasks(), inst.tasks());
        assert!(!plain.has_teams());
    }

    #[test]
    fn a_family_is_drawn_by_name_and_the_knobs_beside_it_override_it() {
        let family = |flags: &str| {
            generate(&gen_args(&format!(
                "--robots 60 --tasks 6 --seed 2 {flags} --out x.jsonl"
            )))
        };
        let drawn = &family("--family void-capacity").unwrap()[0];
        let by_library = afg_game::Family::VoidCapacity
            .config(60, 6, 2)
            .unwrap()
            .generate()
            .unwrap();
        assert_eq!(drawn, &by_library);
        let lighter = &family("--family void-capacity --beta 0.5").unwrap()[0];
        assert!(lighter.allows_void() && lighter.beta() == 0.5);
        let Err(err) = crate::parse("gen --robots 6 --family uniformish --out x.jsonl") else {
            panic!("an unknown family was read")
        };
        assert!(err.to_string().contains("one of scarce, skills"), "{err}");
    }

    #[test]
    fn bad_knobs_are_clear_errors() {
        for (flags, needle) in [
            ("--robots 10 --eps 1.2 --out x.jsonl", "eps"),
            ("--robots 0 --out x.jsonl", "robot"),
            (
                "--robots 10 --capacity-slack 0.5 --out x.jsonl",
                "capacity slack must be at least 1 (got 0.5)",
            ),
            ("--robots 10 --count 0 --out x.jsonl", "count"),
            ("--robots 10 --rewards 5,2 --out x.jsonl", "reward"),
            ("--robots 10 --rewards 5 --out x.jsonl", "two numbers"),
            ("--robots 10 --min-team 0,3 --out x.jsonl", "at least 1"),
            ("--robots 10 --min-team 4,3 --out x.jsonl", "empty"),
            (
                "--robots 10 --min-team 2 --out x.jsonl",
                "--min-team takes two",
            ),
            (
                "--robots 10 --skills 2 --skill-share 1.5 --out x.jsonl",
                "share",
            ),
            ("--robots 10 --requires 1,2 --out x.jsonl", "need skills"),
        ] {
            let err = generate(&gen_args(flags)).unwrap_err();
            assert!(
                format!("{err:#}").to_lowercase().contains(needle),
                "{flags}: {err:#}"
            );
        }
    }
}

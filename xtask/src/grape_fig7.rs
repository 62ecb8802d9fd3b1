//! GRAPE's published Fig. 7 runs beside afg's: the committed dataset
//! `datasets/grape-fig7/` (converted from GRAPE's `.mat` files by
//! `scripts/grape_fig7.py`), and the table `cargo xtask grape-fig7` prints.
//!
//! Per run: GRAPE's published utility, changes and rounds; its published partition
//! scored by afg; afg's GRAPE DA centrally and decentralised over the run's own
//! communication graph (robots within 50 m); balanced DA; and the exact optimum with
//! and without the void task. Every welfare is also given as % of the void optimum,
//! the optimum of GRAPE's game.
//!
//! `cargo xtask grape-fig7`: GRAPE's published Fig. 7 runs beside afg's, as the
//! Markdown table of docs/baselines.md.

use std::fmt::Write as _;
use std::path::Path;

use afg_baseline::{
    Allocator, CentralisedDa, DecentralisedDa, DecentralisedRun, Optimum, percent_of_opt,
};
use afg_eval::EvalError;
use afg_game::io::read_dataset;
use afg_game::{Assignment, GameError, Instance, Preference};
use afg_graph::GraphKind;
use serde::Deserialize;

/// The dataset's directory, from the workspace root.
pub const DATASET: &str = "datasets/grape-fig7";

/// What GRAPE's authors published for one run (`published.json`).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PublishedRun {
    /// `circle`, `skew` or `square`: how the robots were deployed.
    pub name: String,
    /// The `.mat` file it was converted from.
    pub file: String,
    /// GRAPE's global utility (`Global_GRAPE`): the sum of the robots' utilities.
    pub utility: f64,
    /// Its final evolution number (`iteration`): the changes on the winning chain.
    pub changes: u64,
    /// Its rounds until every robot was satisfied (`final_time`).
    pub rounds: u64,
    /// Robots within this distance hear each other (metres).
    pub communication_range: f64,
    /// Links of the communication graph.
    pub links: usize,
}

/// `published.json`: where the runs come from, and what was published.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PublishedFile {
    format: String,
    version: u32,
    source: String,
    commit: String,
    directory: String,
    licence: String,
    runs: Vec<PublishedRun>,
}

/// One published run: the instance, GRAPE's final partition and its numbers.
#[derive(Clone, Debug)]
pub struct GrapeRun {
    /// The instance (GRAPE's game: the void task allowed).
    pub instance: Instance,
    /// GRAPE's final partition.
    pub partition: Assignment,
    /// GRAPE's published numbers.
    pub published: PublishedRun,
}

/// Reads the three runs of `dir` (normally [`DATASET`] under the workspace root).
///
/// # Errors
/// [`EvalError::Game`] if a file is missing or unreadable, [`EvalError::BadFile`] if
/// `published.json` is of another format or the files disagree on the runs.
///
/// # Examples
/// ```
/// let root = xtask::repo_root();
/// let runs = xtask::grape_fig7::read_runs(&root.join(xtask::grape_fig7::DATASET))?;
/// assert_eq!(runs.len(), 3);
/// assert!(runs.iter().all(|r| r.instance.allows_void() && r.instance.num_robots() == 320));
/// # Ok::<(), afg_eval::EvalError>(())
/// ```
pub fn read_runs(dir: &Path) -> Result<Vec<GrapeRun>, EvalError> {
    let published = read_published(dir)?;
    let instances = read_dataset(&dir.join("instances.jsonl"))?;
    let partitions_path = dir.join("grape-partitions.jsonl");
    let text = read_text(&partitions_path)?;
    let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
    if instances.len() != published.runs.len() || lines.len() != published.runs.len() {
        return Err(EvalError::BadFile {
            path: dir.display().to_string(),
            message: format!(
                "{} instances, {} partitions and {} published runs",
                instances.len(),
                lines.len(),
                published.runs.len()
            ),
        });
    }
    let in_partitions = |source| GameError::InFile {
        path: partitions_path.display().to_string(),
        source: Box::new(source),
    };
    instances
        .into_iter()
        .zip(lines)
        .zip(published.runs)
        .map(|((instance, line), published)| {
            let partition = Assignment::from_json(line, &instance).map_err(in_partitions)?;
            Ok(GrapeRun {
                instance,
                partition,
                published,
            })
        })
        .collect()
}

/// The source of the runs, as `published.json` names it: repository, commit, licence.
///
/// # Errors
/// As [`read_runs`].
pub fn source(dir: &Path) -> Result<String, EvalError> {
    let file = read_published(dir)?;
    Ok(format!(
        "{} at commit {}, {}/ ({} licence)",
        file.source,
        file.commit.get(..7).unwrap_or(&file.commit),
        file.directory,
        file.licence
    ))
}

fn read_text(path: &Path) -> Result<String, EvalError> {
    std::fs::read_to_string(path).map_err(|source| {
        EvalError::Game(GameError::Io {
            path: path.display().to_string(),
            source,
        })
    })
}

/// `published.json` of `dir`, checked to be of its format.
fn read_published(dir: &Path) -> Result<PublishedFile, EvalError> {
    let path = dir.join("published.json");
    let file: PublishedFile = serde_json::from_str(&read_text(&path)?).map_err(|source| {
        EvalError::Game(GameError::InFile {
            path: path.display().to_string(),
            source: Box::new(GameError::Json { line: None, source }),
        })
    })?;
    if file.format != "afg-grape-published" || file.version != 1 {
        return Err(EvalError::BadFile {
            path: path.display().to_string(),
            message: format!(
                "expected format \"afg-grape-published\" version 1, found \"{}\" version {}",
                file.format, file.version
            ),
        });
    }
    Ok(file)
}

/// The seed of afg's decentralised GRAPE (its random time stamps).
pub const SEED: u64 = 0;

/// One row of the table.
struct Row {
    run: String,
    welfare: f64,
    /// Robots in the void task; `None` where not known.
    out: Option<usize>,
    ns_selfish: Option<f64>,
    ns_balanced: Option<f64>,
    changes: Option<u64>,
    rounds: Option<u64>,
    messages: Option<u64>,
}

impl Row {
    /// Appends this row to a Markdown table, with its welfare as % of `best`.
    fn write(&self, out: &mut String, best: f64) {
        let count = |x: Option<u64>| x.map_or("—".into(), |v| v.to_string());
        let rate = |x: Option<f64>| x.map_or("—".into(), |v| format!("{:.1} %", 100.0 * v));
        let percent =
            percent_of_opt(self.welfare, best).map_or("—".into(), |v| format!("{v:.2} %"));
        let _ = writeln!(
            out,
            "| {} | {:.1} | {percent} | {} | {} | {} | {} | {} | {} |",
            self.run,
            self.welfare,
            self.out.map_or("—".into(), |v| v.to_string()),
            rate(self.ns_selfish),
            rate(self.ns_balanced),
            count(self.changes),
            count(self.rounds),
            count(self.messages),
        );
    }

    /// The row of `assignment`, judged by afg.
    fn scored(run: &str, instance: &Instance, assignment: &Assignment) -> Row {
        Row {
            run: run.into(),
            welfare: instance.welfare(assignment),
            out: Some(instance.num_robots() - assignment.num_assigned()),
            ns_selfish: Some(instance.ns_rate(assignment, Preference::Selfish)),
            ns_balanced: Some(instance.ns_rate(assignment, Preference::Balanced)),
            changes: None,
            rounds: None,
            messages: None,
        }
    }
}

/// The Markdown table: for each run, GRAPE's published numbers and afg's (see the
/// module docs).
///
/// # Errors
/// As [`read_runs`], and the allocators' errors.
pub fn table(dir: &Path) -> Result<String, EvalError> {
    let mut out = String::new();
    for run in read_runs(dir)? {
        let (inst, p) = (&run.instance, &run.published);
        let decentralised = DecentralisedDa {
            preference: Preference::Selfish,
            graph: GraphKind::Radius {
                radius: p.communication_range,
            },
            seed: SEED,
        }
        .run(inst)?;
        let void_opt = Optimum.allocate(inst)?.assignment;
        let best = inst.welfare(&void_opt);
        let added = match decentralised.added_edges {
            0 => String::new(),
            k => format!(", {k} added to connect it"),
        };
        let _ = writeln!(
            out,
            "**{}** (`{}`: N = {}, M = {}, {} links within {} m{added})\n",
            p.name,
            p.file,
            inst.num_robots(),
            inst.num_tasks(),
            p.links,
            p.communication_range,
        );
        out.push_str(
            "| run | welfare | % of void OPT | robots out | NS_rate selfish | NS_rate balanced | changes | rounds | messages |\n",
        );
        out.push_str("|---|---|---|---|---|---|---|---|---|\n");
        for row in rows(&run, &decentralised, &void_opt)? {
            row.write(&mut out, best);
        }
        let stats = decentralised.allocation.stats;
        let ours = inst.welfare(&decentralised.allocation.assignment);
        let _ = writeln!(
            out,
            "\nafg's decentralised GRAPE: welfare {:+.3} % against GRAPE's published utility, {} rounds against its {}.\n",
            100.0 * (ours - p.utility) / p.utility,
            stats.rounds,
            p.rounds
        );
    }
    Ok(out)
}

/// The rows of one run, given afg's GRAPE over its graph and the optimum of its game.
fn rows(
    run: &GrapeRun,
    decentralised: &DecentralisedRun,
    void_opt: &Assignment,
) -> Result<Vec<Row>, EvalError> {
    let (inst, p) = (&run.instance, &run.published);
    let paper = Instance::new(inst.robots().to_vec(), inst.tasks().to_vec(), inst.beta())?;
    let paper_opt = Optimum.allocate(&paper)?.assignment;
    let central = CentralisedDa::new(Preference::Selfish).allocate(inst)?;
    let balanced = CentralisedDa::new(Preference::Balanced).allocate(inst)?;
    let stats = decentralised.allocation.stats;
    let decentralised_name = format!(
        "GRAPE, decentralised over the {} m graph (afg, seed {SEED})",
        p.communication_range
    );
    Ok(vec![
        Row {
            run: "GRAPE, published (MATLAB)".into(),
            welfare: p.utility,
            out: None,
            ns_selfish: None,
            ns_balanced: None,
            changes: Some(p.changes),
            rounds: Some(p.rounds),
            messages: None,
        },
        Row::scored(
            "GRAPE's published partition, scored by afg",
            inst,
            &run.partition,
        ),
        Row {
            changes: Some(central.stats.iterations),
            ..Row::scored("GRAPE DA, centralised (afg)", inst, &central.assignment)
        },
        Row {
            changes: Some(stats.iterations),
            rounds: Some(stats.rounds),
            messages: Some(stats.messages),
            ..Row::scored(
                &decentralised_name,
                inst,
                &decentralised.allocation.assignment,
            )
        },
        Row {
            changes: Some(balanced.stats.iterations),
            ..Row::scored("balanced DA (afg)", inst, &balanced.assignment)
        },
        Row::scored("OPT, void allowed (GRAPE's game)", inst, void_opt),
        Row::scored(
            "OPT, every robot placed (the paper's game)",
            inst,
            &paper_opt,
        ),
    ])
}

// The command.
use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

/// Where the converted runs are.
#[derive(Args)]
pub struct GrapeArgs {
    /// The directory of the converted runs (written by scripts/grape_fig7.py).
    #[arg(long, default_value = DATASET)]
    dataset: PathBuf,
}

/// Prints the source of the runs and the table.
pub fn run(args: GrapeArgs) -> Result<()> {
    println!("GRAPE's runs: {}\n", source(&args.dataset)?);
    print!("{}", table(&args.dataset)?);
    Ok(())
}

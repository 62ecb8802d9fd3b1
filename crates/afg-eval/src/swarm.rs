//! The swarm study behind `afg swarm`: a grid of decentralised methods × instances ×
//! loss rates × failing shares, several seeds a cell, each cell's runs summarised in
//! one row of a Markdown table.

use std::fmt::Write as _;
use std::ops::Range;
use std::time::Duration;

use afg_baseline::{Failure, Network, Swarm, SwarmMethod, SwarmReport};
use afg_game::Instance;
use afg_graph::GraphKind;
use rayon::prelude::*;

use crate::EvalError;
use crate::report::duration;

/// A grid of swarm runs: one cell per method × instance × loss × failing share, each
/// run for every seed.
#[derive(Clone, Debug)]
pub struct SwarmGrid {
    /// The decentralised methods.
    pub methods: Vec<SwarmMethod>,
    /// The instances.
    pub instances: Vec<Instance>,
    /// The network of every cell but its loss and failure.
    pub network: Network,
    /// Long-run shares of messages lost, one cell each.
    pub losses: Vec<f64>,
    /// Shares of the robots that crash, one cell each (0: none).
    pub failing: Vec<f64>,
    /// The round they crash at; `None`: mid-run, half the rounds the same run takes
    /// without failures.
    pub fail_at: Option<u64>,
    /// Silent rounds before a neighbour removes a crashed robot.
    pub detect_after: u64,
    /// The seeds of each cell.
    pub seeds: Range<u64>,
    /// [`Swarm::max_rounds`] (0: GRAPE's bound, stretched).
    pub max_rounds: u64,
    /// Whether the runs keep a trace (for figures).
    pub trace: bool,
}

/// One cell of the grid: a method, an instance and a network, run over the seeds.
#[derive(Clone, Debug)]
pub struct Cell {
    /// The method.
    pub method: SwarmMethod,
    /// The instance.
    pub instance: Instance,
    /// The network, its failure included.
    pub network: Network,
    /// Whether the crash round is left to mid-run.
    pub crash_mid_run: bool,
}

impl SwarmGrid {
    /// The grid's cells, each network checked.
    ///
    /// # Errors
    /// [`EvalError::Alloc`] for a network knob out of range; [`EvalError::NoInstances`]
    /// for an empty grid.
    pub fn cells(&self) -> Result<Vec<Cell>, EvalError> {
        let mut cells = Vec::new();
        for &method in &self.methods {
            for instance in &self.instances {
                for &loss in &self.losses {
                    for &fail in &self.failing {
                        let failure = (fail > 0.0).then(|| Failure {
                            fraction: fail,
                            at_round: self.fail_at.unwrap_or(1),
                            detect_after: self.detect_after,
                        });
                        let network = Network {
                            loss,
                            failure,
                            ..self.network.clone()
                        };
                        network.check()?;
                        cells.push(Cell {
                            method,
                            instance: instance.clone(),
                            network,
                            crash_mid_run: fail > 0.0 && self.fail_at.is_none(),
                        });
                    }
                }
            }
        }
        if cells.is_empty() || self.seeds.is_empty() {
            return Err(EvalError::NoInstances);
        }
        Ok(cells)
    }

    /// How many runs [`SwarmGrid::run`] makes: every cell for every seed (a progress
    /// bar's length), without building the cells.
    pub fn run_count(&self) -> usize {
        let seeds = self.seeds.end.saturating_sub(self.seeds.start) as usize;
        self.methods.len() * self.instances.len() * self.losses.len() * self.failing.len() * seeds
    }

    /// Every cell for every seed, in parallel: `(cell index, report)` in cell and seed
    /// order. `on_run` is called after each run; `on_round` sees the rounds of a grid of
    /// one run (a progress bar).
    ///
    /// # Errors
    /// As [`SwarmGrid::cells`], and the runs' errors.
    ///
    /// # Examples
    /// ```
    /// use afg_baseline::{Network, SwarmMethod};
    /// use afg_eval::swarm::{SwarmGrid, table};
    /// use afg_game::{GeneratorConfig, Preference};
    /// let grid = SwarmGrid {
    ///     methods: vec![SwarmMethod::Grape { preference: Preference::Selfish }],
    ///     instances: vec![GeneratorConfig::paper(20, 3, 1).generate()?],
    ///     network: Network::default(),
    ///     losses: vec![0.0, 0.3],
    ///     failing: vec![0.0],
    ///     fail_at: None,
    ///     detect_after: 3,
    ///     seeds: 0..2,
    ///     max_rounds: 0,
    ///     trace: false,
    /// };
    /// let (cells, reports) = grid.run(|| {}, &|_| {})?;
    /// assert_eq!((cells.len(), reports.len()), (2, 4));
    /// assert_eq!(grid.run_count(), reports.len());
    /// assert!(reports.iter().all(|(_, r)| r.converged));
    /// assert_eq!(table(&cells, &reports).lines().count(), 2 + 2);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    #[allow(clippy::type_complexity)]
    pub fn run(
        &self,
        on_run: impl Fn() + Sync,
        on_round: &(dyn Fn(u64) + Sync),
    ) -> Result<(Vec<Cell>, Vec<(usize, SwarmReport)>), EvalError> {
        let cells = self.cells()?;
        let jobs: Vec<(usize, u64)> = (0..cells.len())
            .flat_map(|c| self.seeds.clone().map(move |s| (c, s)))
            .collect();
        let single = jobs.len() == 1;
        let no_rounds = |_: u64| {};
        let on_round: &(dyn Fn(u64) + Sync) = if single { on_round } else { &no_rounds };
        let reports = jobs
            .par_iter()
            .map(|&(c, seed)| {
                let report = self.run_one(&cells[c], seed, on_round)?;
                on_run();
                Ok((c, report))
            })
            .collect::<Result<_, EvalError>>()?;
        Ok((cells, reports))
    }

    /// One seed of one cell; a mid-run crash is placed at half the rounds of the same
    /// run without failures.
    fn run_one(
        &self,
        cell: &Cell,
        seed: u64,
        on_round: &(dyn Fn(u64) + Sync),
    ) -> Result<SwarmReport, EvalError> {
        let swarm = |network: Network| {
            let mut swarm = match cell.method {
                SwarmMethod::Grape { preference } => Swarm::grape(preference, network, seed),
                SwarmMethod::Auction { epsilon } => Swarm::auction(epsilon, network, seed),
            };
            swarm.max_rounds = self.max_rounds;
            swarm.trace = self.trace;
            swarm
        };
        let mut network = cell.network.clone();
        if cell.crash_mid_run {
            let intact = Network {
                failure: None,
                ..network.clone()
            };
            let rounds = swarm(intact).run(&cell.instance)?.rounds;
            if let Some(f) = network.failure.as_mut() {
                f.at_round = (rounds / 2).max(1);
            }
        }
        Ok(swarm(network).run_with(&cell.instance, on_round)?)
    }
}

impl Cell {
    /// What the cell is, in a few words: `GRAPE, N = 40, loss 30 %, 20 % fail`.
    pub fn label(&self) -> String {
        let network = &self.network;
        let method = match self.method {
            SwarmMethod::Grape { .. } => "GRAPE".to_string(),
            SwarmMethod::Auction { epsilon } => format!("auction (ε = {epsilon})"),
        };
        let mut parts = vec![method, format!("N = {}", self.instance.num_robots())];
        match network.graph {
            GraphKind::Radius { radius } => parts.push(format!("radius {radius}")),
            GraphKind::Knn { k } if k != 10 => parts.push(format!("{k} nearest")),
            GraphKind::Knn { .. } | GraphKind::Complete => {}
        }
        parts.push(format!("loss {:.0} %", 100.0 * network.loss));
        if let Some(b) = network.burst {
            parts.push(format!("bursts of {b}"));
        }
        if network.max_delay > 0 {
            parts.push(format!("delay ≤ {}", network.max_delay));
        }
        if network.activation < 1.0 {
            parts.push(format!("async {}", network.activation));
        }
        if let Some(f) = network.failure {
            parts.push(format!("{:.0} % fail", 100.0 * f.fraction));
        }
        if let Some(r) = network.partition_until {
            parts.push(format!("split until {r}"));
        }
        parts.join(", ")
    }
}

/// The Markdown table of a grid's runs: one row per cell, means over its seeds.
pub fn table(cells: &[Cell], reports: &[(usize, SwarmReport)]) -> String {
    let mut out = String::from(
        "| network | links added | runs converged | fail at | rounds | messages | MB (partitions) | MB (changes) | agreeing | % of OPT (survivors) | stable | NS_rate balanced | NS_rate selfish | time |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for (c, cell) in cells.iter().enumerate() {
        let runs: Vec<&SwarmReport> = reports
            .iter()
            .filter(|(k, _)| *k == c)
            .map(|(_, r)| r)
            .collect();
        out += &row(cell, &runs);
    }
    out
}

/// Where several instances share a method, a size and a network (the rows of
/// [`table`] that read alike), one line per such group: its runs, how many converged,
/// the mean % of OPT with the least and largest, and the mean rounds; `None` where no
/// two cells share one.
pub fn summary(cells: &[Cell], reports: &[(usize, SwarmReport)]) -> Option<String> {
    let mut groups: Vec<(String, Vec<&SwarmReport>)> = Vec::new();
    for (c, cell) in cells.iter().enumerate() {
        let label = cell.label();
        let runs = reports.iter().filter(|(k, _)| *k == c).map(|(_, r)| r);
        match groups.iter_mut().find(|(l, _)| *l == label) {
            Some((_, group)) => group.extend(runs),
            None => groups.push((label, runs.collect())),
        }
    }
    if groups.len() == cells.len() {
        return None;
    }
    let mut out = String::from(
        "| network | runs | converged | % of OPT, mean (least–largest) | rounds, mean |\n|---|---|---|---|---|\n",
    );
    for (label, runs) in &groups {
        let percents: Option<Vec<f64>> = runs.iter().map(|r| r.percent_of_opt).collect();
        let percent = percents
            .filter(|p| !p.is_empty())
            .map_or("–".to_owned(), |p| {
                let (lo, hi) = p
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
                        (lo.min(x), hi.max(x))
                    });
                format!(
                    "{:.2} % ({lo:.2}–{hi:.2})",
                    p.iter().sum::<f64>() / p.len() as f64
                )
            });
        let rounds = runs.iter().map(|r| r.rounds as f64).sum::<f64>() / runs.len().max(1) as f64;
        let converged = runs.iter().filter(|r| r.converged).count();
        let _ = writeln!(
            out,
            "| {label} | {} | {converged} | {percent} | {rounds:.0} |",
            runs.len()
        );
    }
    Some(out)
}

/// One cell's row of [`table`].
fn row(cell: &Cell, runs: &[&SwarmReport]) -> String {
    let mean = |f: &dyn Fn(&SwarmReport) -> f64| {
        runs.iter().map(|r| f(r)).sum::<f64>() / runs.len() as f64
    };
    let count = |f: &dyn Fn(&SwarmReport) -> bool| runs.iter().filter(|r| f(r)).count();
    let fail_at = cell.network.failure.map_or("–".to_string(), |_| {
        let rounds: Vec<String> = runs
            .iter()
            .map(|r| r.network.failure.map_or(0, |f| f.at_round).to_string())
            .collect();
        rounds.join("/")
    });
    let percent = runs
        .iter()
        .map(|r| r.percent_of_opt)
        .collect::<Option<Vec<f64>>>()
        .map_or("–".to_string(), |p| {
            format!("{:.2} %", p.iter().sum::<f64>() / p.len() as f64)
        });
    format!(
        "| {} | {:.0} | {}/{} | {} | {:.0} | {:.0} | {:.1} | {:.2} | {:.1} % | {} | {}/{} | {:.1} % | {:.1} % | {} |\n",
        cell.label(),
        mean(&|r| r.added_edges as f64),
        count(&|r| r.converged),
        runs.len(),
        fail_at,
        mean(&|r| r.rounds as f64),
        mean(&|r| r.messages as f64),
        mean(&|r| r.bytes as f64) / 1e6,
        mean(&|r| r.delta_bytes as f64) / 1e6,
        100.0 * mean(&|r| r.agreeing),
        percent,
        count(&|r| r.stable),
        runs.len(),
        100.0 * mean(&|r| r.ns_rate_balanced),
        100.0 * mean(&|r| r.ns_rate_selfish),
        duration(Duration::from_secs_f64(mean(&|r| r.wall_time_s))),
    )
}

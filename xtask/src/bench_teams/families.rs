//! `cargo xtask bench-teams --families`: per named family and size, the time afg's
//! exact solver takes to prove the optimum beside HiGHS' and CP-SAT's, and every
//! allocator's share of the best proven bound, worst instance beside the mean.

use afg_baseline::Allocator;
use afg_game::Family;
use afg_learn::run::{ModelOptions, load_model};
use anyhow::{Context, Result};

use super::{BenchTeamsArgs, Row, peer_columns, percent};

/// `--families`: names, or `all`.
pub(super) fn parse(text: &str) -> Result<Vec<Family>, String> {
    match text {
        "all" => Ok(Family::ALL.to_vec()),
        name => name.parse().map(|family| vec![family]),
    }
}

/// The committed staffing models, each labelled "(ours)": the threshold model and
/// the skill model (each refuses the games it was not made for), each also with its
/// repair (`--repair`: the welfare climb after the placement).
pub(super) fn staffing_models() -> Result<Vec<(String, Box<dyn Allocator>)>> {
    let mut models = Vec::new();
    for name in ["staffing_teams", "staffing_skills"] {
        let dir = crate::repo_root().join("models/ours").join(name);
        for (repair, label) in [(false, ""), (true, " + repair")] {
            let options = ModelOptions {
                repair,
                ..ModelOptions::default()
            };
            let model =
                load_model(&dir, options).with_context(|| format!("loading {}", dir.display()))?;
            models.push((format!("{name}{label} (ours)"), model));
        }
    }
    Ok(models)
}

/// The geometric mean of `values`.
fn geometric_mean(values: &[f64]) -> f64 {
    (values.iter().map(|v| v.ln()).sum::<f64>() / values.len() as f64).exp()
}

/// The families' tables, in Markdown.
pub(super) fn markdown(rows: &[Row], args: &BenchTeamsArgs) -> String {
    let mut groups: Vec<Vec<&Row>> = Vec::new();
    for row in rows {
        match groups
            .iter_mut()
            .find(|g| (g[0].family, g[0].robots, g[0].tasks) == (row.family, row.robots, row.tasks))
        {
            Some(group) => group.push(row),
            None => groups.push(vec![row]),
        }
    }
    let peers = peer_columns(rows);
    let mut md = format!(
        "Time to proof, per family and size ({} instances each; afg on one core, limit {} s; \
         a peer that did not prove the optimum counts its whole budget, marked ≥; ratio: \
         the peer's time over afg's, geometric mean and the lowest instance — below 1 \
         where afg was slower; afg's worst gap: its certified gap when it stopped, the \
         largest of the family's instances):\n\n| family | N | M | afg time mean / worst | afg proven | afg worst gap |",
        args.instances, args.time_limit
    );
    for (name, budget) in &peers {
        md += &format!(" {name} {budget}s time mean / worst | proven | ratio geo / lowest |");
    }
    md += "\n|---|---|---|---|---|---|";
    md += &"---|---|---|".repeat(peers.len());
    md.push('\n');
    for group in &groups {
        let r0 = group[0];
        let afg: Vec<(f64, bool)> = group
            .iter()
            .map(|r| (r.afg.seconds, r.afg.proven))
            .collect();
        let worst_gap = group
            .iter()
            .map(|r| afg_baseline::certified_gap(r.afg.bound, r.afg.welfare))
            .fold(0.0, f64::max);
        md += &format!(
            "| {} | {} | {} | {} | {}/{} | {:.3} % |",
            r0.family.map_or("—".into(), |f| f.to_string()),
            r0.robots,
            r0.tasks,
            times(&afg),
            afg.iter().filter(|t| t.1).count(),
            group.len(),
            100.0 * worst_gap
        );
        for p in 0..peers.len() {
            if group.iter().any(|r| r.peers.len() <= p) {
                md += " — | — | — |";
                continue;
            }
            let theirs: Vec<(f64, bool)> = group
                .iter()
                .map(|r| (r.peers[p].seconds, r.peers[p].status == "optimal"))
                .collect();
            let ratios: Vec<f64> = theirs
                .iter()
                .zip(&afg)
                .map(|(t, a)| t.0 / a.0.max(1e-6))
                .collect();
            md += &format!(
                " {} | {}/{} | {:.1}× / {:.2}× |",
                times(&theirs),
                theirs.iter().filter(|t| t.1).count(),
                group.len(),
                geometric_mean(&ratios),
                ratios.iter().copied().fold(f64::INFINITY, f64::min)
            );
        }
        md.push('\n');
    }
    md + "\n" + &allocators(&groups)
}

/// "mean / worst" seconds of (seconds, proven) runs (a run not proven took its whole
/// budget: a lower bound on its time to proof), each marked ≥ where it includes an unproven run.
fn times(runs: &[(f64, bool)]) -> String {
    let mean = runs.iter().map(|t| t.0).sum::<f64>() / runs.len() as f64;
    let worst = runs
        .iter()
        .copied()
        .fold((0.0, true), |w, t| if t.0 > w.0 { t } else { w });
    let mark = |proven: bool| if proven { "" } else { "≥ " };
    let all = runs.iter().all(|t| t.1);
    format!(
        "{}{mean:.3} s / {}{:.3} s",
        mark(all),
        mark(worst.1),
        worst.0
    )
}

/// Each allocator's share of the best proven bound per family and size: the mean and
/// the worst instance, or how many instances it refused.
fn allocators(groups: &[Vec<&Row>]) -> String {
    let Some(first) = groups.iter().flatten().find(|r| !r.allocators.is_empty()) else {
        return String::new();
    };
    let names: Vec<&str> = first.allocators.iter().map(|a| a.0.as_str()).collect();
    let mut md =
        "Allocators (% of the best proven bound: mean / worst instance):\n\n| family | N | M |"
            .to_owned();
    for name in &names {
        md += &format!(" {name} |");
    }
    md += "\n|---|---|---|";
    md += &"---|".repeat(names.len());
    md.push('\n');
    for group in groups.iter().filter(|g| !g[0].allocators.is_empty()) {
        let r0 = group[0];
        md += &format!(
            "| {} | {} | {} |",
            r0.family.map_or("—".into(), |f| f.to_string()),
            r0.robots,
            r0.tasks
        );
        for a in 0..names.len() {
            let shares: Vec<f64> = group
                .iter()
                .filter_map(|r| r.allocators[a].1.map(|w| percent(w, r.best_bound)))
                .collect();
            let cell = if shares.len() == group.len() {
                let mean = shares.iter().sum::<f64>() / shares.len() as f64;
                let worst = shares.iter().copied().fold(f64::INFINITY, f64::min);
                format!("{mean:.1} / {worst:.1}")
            } else {
                format!("refused {}/{}", group.len() - shares.len(), group.len())
            };
            md += &format!(" {cell} |");
        }
        md.push('\n');
    }
    md
}

//! The tables in Markdown, the headline under them and the list of committed models.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Duration;

use afg_baseline::Method;
use afg_learn::run::RunRecord;

use super::{RowId, Run, Scale};
use afg_eval::report::duration;
use afg_eval::{EvalError, Summary, dataset};

use crate::{ModelSpec, paper};

/// The measured cells both tables share: welfare, % of OPT, the two NS_rates and the
/// time per instance.
const MEASURED_HEADER: &str =
    "welfare | % of OPT | NS_rate balanced | NS_rate selfish | time / instance";

fn measured_cells(r: &Summary) -> String {
    format!(
        "{:.2} | {:.2} % | {:.1} % | {:.1} % | {}",
        r.welfare,
        r.percent_of_opt,
        r.ns_rate_balanced,
        r.ns_rate_selfish,
        duration(Duration::from_secs_f64(r.seconds_per_instance))
    )
}

/// Table I in Markdown: per N, every row with the paper's welfare beside the paper's
/// models (and its NS_rate beside AFGNet_DDQN).
///
/// # Panics
/// If a scale is not one the paper reports (20, 60, 100), or `scales` is empty.
pub fn table1_markdown(scales: &[Scale]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "### Table I — mean over the first {} instances of each test set\n",
        scales[0].rows[0].summary.instances
    );
    for scale in scales {
        let n = scale.robots;
        let paper = paper::table1(n).expect("the paper reports every N of Table I");
        let _ = writeln!(
            s,
            "**N = {n}** (paper: S2V_DDQN {}, AFGNet_DQN {}, AFGNet_DDQN {}, NS_rate {} %)\n",
            paper.s2v_ddqn, paper.afgnet_dqn, paper.afgnet_ddqn, paper.afgnet_ddqn_ns_rate
        );
        let _ = writeln!(s, "| method | {MEASURED_HEADER} | paper welfare |");
        let _ = writeln!(s, "|---|---|---|---|---|---|---|");
        for row in &scale.rows {
            let reported = match row.id {
                RowId::Model { spec, .. } if row.id.is_paper_row() => {
                    match paper.welfare_of(&spec) {
                        Some(w) if spec == ModelSpec::afgnet_ddqn(n) => {
                            format!("{w} (NS {} %)", paper.afgnet_ddqn_ns_rate)
                        }
                        Some(w) => format!("{w}"),
                        None => "–".into(),
                    }
                }
                _ => "–".into(),
            };
            let r = &row.summary;
            let _ = writeln!(s, "| {} | {} | {reported} |", r.method, measured_cells(r));
        }
        let _ = writeln!(s);
    }
    s
}

/// Table II in Markdown: per N, every row with its instance count (the slow rows, the
/// decentralised simulation and the exact learned rollouts, run on fewer instances),
/// under the paper's DA and Pretrain_60 numbers.
///
/// # Panics
/// If a scale is not one the paper reports (500, 1000), or `scales` is empty.
pub fn table2_markdown(scales: &[Scale]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "### Table II — large swarms (the first {} instances; the slowest rows on fewer, see the instances column)\n",
        scales[0].rows[0].summary.instances
    );
    for scale in scales {
        let n = scale.robots;
        let paper = paper::table2(n).expect("the paper reports every N of Table II");
        let _ = writeln!(
            s,
            "**N = {n}** (paper: DA {} in {} s, NS {} %; Pretrain_60 {} in {} s, NS {} %)\n",
            paper.da_welfare,
            paper.da_seconds,
            paper.da_ns_rate,
            paper.pretrain60_welfare,
            paper.pretrain60_seconds,
            paper.pretrain60_ns_rate
        );
        let _ = writeln!(s, "| method | instances | {MEASURED_HEADER} |");
        let _ = writeln!(s, "|---|---|---|---|---|---|---|");
        for row in &scale.rows {
            let r = &row.summary;
            let _ = writeln!(
                s,
                "| {} | {} | {} |",
                r.method,
                r.instances,
                measured_cells(r)
            );
        }
        let _ = writeln!(s);
    }
    s
}

/// The honest headline: AFGNet_DDQN against GRAPE DA, greedy and nearest at each N of
/// Table I, in numbers.
pub fn headline(table1: &[Scale]) -> String {
    let mut s = String::from("**Headline.** ");
    for scale in table1 {
        let n = scale.robots;
        let find = |id: RowId| scale.rows.iter().find(|r| r.id == id);
        let get = |m: Method| find(RowId::Method(m)).map(|r| r.summary.percent_of_opt);
        let (Some(da), Some(greedy), Some(nearest)) =
            (get(Method::Da), get(Method::Greedy), get(Method::Nearest))
        else {
            continue;
        };
        let drl = find(RowId::Model {
            spec: ModelSpec::afgnet_ddqn(n),
            robots: n,
            run: Run::AS_TRAINED,
        });
        let _ = match drl {
            Some(drl) => write!(
                s,
                "At N = {n}, AFGNet_DDQN reaches {:.1} % of OPT, against {da:.1} % for GRAPE DA, {greedy:.1} % for one-pass greedy and {nearest:.1} % for nearest-task. ",
                drl.summary.percent_of_opt
            ),
            None => write!(
                s,
                "At N = {n} no AFGNet_DDQN model is committed yet; GRAPE DA reaches {da:.1} % of OPT, greedy {greedy:.1} % and nearest {nearest:.1} %. ",
            ),
        };
    }
    s
}

/// The training budget of every committed model the tables use, from its run
/// directory's manifest and configuration: a Markdown section with the command that
/// retrains each.
///
/// # Errors
/// A committed manifest or configuration that cannot be read.
pub fn models_table(root: &Path) -> Result<String, EvalError> {
    let mut md = String::from(
        "\n## The committed models\n\n\
         Each row's command retrains it (`manifest.json` beside the weights; \
         wall times are those of runs that shared the 2 cores with other work).\n\n\
         | model | N | steps | learning rate | wall time | final validation, % of OPT | command |\n\
         |---|---|---|---|---|---|---|\n",
    );
    let specs = (0..ModelSpec::table1(0).len())
        .flat_map(|kind| dataset::TABLE1_SIZES.map(|n| ModelSpec::table1(n)[kind]))
        .chain(
            ModelSpec::TRANSFERRED
                .into_iter()
                .filter(|s| !ModelSpec::table1(s.trained_at).contains(s)),
        )
        .chain(ModelSpec::WARM_STARTS)
        .chain(ModelSpec::PRICE_HEADED);
    for spec in specs {
        let run = spec.run_dir(root);
        if !run.has_manifest() {
            continue;
        }
        let manifest = run.manifest()?;
        let config = run.config()?;
        let lr = if config.lr_decay {
            format!(
                "{:.1e} → {:.1e} (annealed)",
                config.lr,
                config.learning_rate(config.steps)
            )
        } else {
            format!("{:.1e} (constant)", config.lr)
        };
        let minutes = manifest.wall_time_s.unwrap_or(f64::NAN) / 60.0;
        let pct = match &manifest.record {
            RunRecord::QNetwork {
                final_validation: Some(v),
                ..
            } => v.percent_of_opt,
            _ => f64::NAN,
        };
        let _ = writeln!(
            md,
            "| {} | {} | {} | {lr} | {minutes:.0} min | {pct:.1} % | `{}` |",
            spec.label(),
            spec.trained_at,
            config.steps,
            manifest.command
        );
    }
    Ok(md)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tables::Row;

    fn row(id: RowId, pct: f64) -> Row {
        let summary = Summary {
            method: id.label(),
            instances: 3,
            welfare: pct / 2.0,
            percent_of_opt: pct,
            ns_rate_balanced: 50.0,
            ns_rate_selfish: 25.0,
            seconds_per_instance: 2e-6,
        };
        Row { id, summary }
    }

    fn scale_60() -> Scale {
        let ddqn = ModelSpec::afgnet_ddqn(60);
        Scale {
            robots: 60,
            rows: vec![
                row(
                    RowId::Model {
                        spec: ddqn,
                        robots: 60,
                        run: Run::AS_TRAINED,
                    },
                    98.0,
                ),
                row(RowId::Method(Method::Da), 98.9),
                row(RowId::Method(Method::Greedy), 98.5),
                row(RowId::Method(Method::Nearest), 98.6),
            ],
        }
    }

    #[test]
    fn table1_puts_the_papers_number_beside_its_model_only() {
        let md = table1_markdown(&[scale_60()]);
        let p = paper::table1(60).unwrap();
        assert!(md.starts_with("### Table I — mean over the first 3 instances"));
        let ddqn_line = md
            .lines()
            .find(|l| l.starts_with("| AFGNet_DDQN |"))
            .unwrap();
        assert_eq!(
            ddqn_line,
            format!(
                "| AFGNet_DDQN | 49.00 | 98.00 % | 50.0 % | 25.0 % | 2.0 µs | {} (NS {} %) |",
                p.afgnet_ddqn, p.afgnet_ddqn_ns_rate
            )
        );
        let da_line = md.lines().find(|l| l.starts_with("| GRAPE DA |")).unwrap();
        assert!(da_line.ends_with("| – |"), "{da_line}");
        // A row labelled like the paper's model but that is not it (a warm start) gets
        // no number: rows are told apart by what they measure, not by their labels.
        let mut impostor = scale_60();
        impostor.rows[0].id = RowId::Model {
            spec: ModelSpec::afgnet_ddqn(60).warm_started_from(20),
            robots: 60,
            run: Run::AS_TRAINED,
        };
        let md = table1_markdown(&[impostor]);
        let line = md
            .lines()
            .find(|l| l.starts_with("| AFGNet_DDQN |"))
            .unwrap();
        assert!(line.ends_with("| – |"), "{line}");
    }

    #[test]
    fn headline_states_each_number() {
        assert_eq!(
            headline(&[scale_60()]),
            "**Headline.** At N = 60, AFGNet_DDQN reaches 98.0 % of OPT, against 98.9 % for GRAPE DA, 98.5 % for one-pass greedy and 98.6 % for nearest-task. "
        );
        let mut no_model = scale_60();
        no_model.rows.remove(0);
        assert!(headline(&[no_model]).contains("no AFGNet_DDQN model is committed yet"));
    }

    #[test]
    fn table2_names_the_instances_of_each_row() {
        let scale = Scale {
            robots: 500,
            rows: vec![row(RowId::Method(Method::Opt), 100.0)],
        };
        let md = table2_markdown(&[scale]);
        assert!(
            md.contains("| OPT | 3 | 50.00 | 100.00 % | 50.0 % | 25.0 % | 2.0 µs |"),
            "{md}"
        );
        assert!(md.contains(&format!(
            "Pretrain_60 {}",
            paper::table2(500).unwrap().pretrain60_welfare
        )));
    }
}

//! The paper's Tables I and II as data, and their Markdown: what
//! `cargo xtask reproduce-tables` prints and writes.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Duration;

use afg_baseline::Method;
use afg_game::Instance;
use afg_learn::{Algo, LearnedPolicy};
use serde::Serialize;

use crate::{EvalError, ModelSpec, PriceSpec, Summary, evaluate, paper};

/// One row of a table: a measured method, and the learned model it measures when it
/// is one of Table I's models at its own scale (then the paper's number stands beside
/// it).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Row {
    /// The measurement.
    #[serde(flatten)]
    pub summary: Summary,
    /// The model, for a Table I model at the scale it was trained at.
    #[serde(skip)]
    pub model: Option<ModelSpec>,
}

impl Row {
    /// A row that is not one of Table I's models at its own scale.
    pub fn new(summary: Summary) -> Self {
        Row {
            summary,
            model: None,
        }
    }

    /// The row of `model` at the scale it was trained at.
    pub fn of_model(model: ModelSpec, summary: Summary) -> Self {
        Row {
            summary,
            model: Some(model),
        }
    }
}

/// The rows of one N.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Scale {
    /// Robots per instance.
    pub robots: usize,
    /// The rows, in table order.
    pub rows: Vec<Row>,
}

/// Every classical method ([`Method::ALL`]) on `insts`, whose optima are `opt`; the
/// decentralised DA (the slowest: a message-passing simulation of the dynamics that
/// [`Method::Da`] runs centrally) on the first `simulated` instances only, and not at
/// all above N = 1000.
///
/// # Errors
/// The allocators' errors.
///
/// # Examples
/// ```
/// use afg_eval::{optima, tables::classical_rows};
/// use afg_game::GeneratorConfig;
/// let insts: Vec<_> = (0..3).map(|s| GeneratorConfig::paper(20, 5, s).generate()).collect::<Result<_, _>>()?;
/// let rows = classical_rows(&insts, &optima(&insts)?, 2)?;
/// let count = |label: &str| rows.iter().find(|r| r.summary.method == label).unwrap().summary.instances;
/// assert_eq!((count("OPT"), count("GRAPE DA, decentralised")), (3, 2));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn classical_rows(
    insts: &[Instance],
    opt: &[f64],
    simulated: usize,
) -> Result<Vec<Row>, EvalError> {
    let n = insts.first().map_or(0, Instance::num_robots);
    let mut rows = Vec::new();
    for method in Method::ALL {
        let k = match method {
            Method::DaDecentralised if n > 1000 => continue,
            Method::DaDecentralised => simulated.min(insts.len()),
            _ => insts.len(),
        };
        rows.push(Row::new(evaluate(
            method.label(),
            method.allocator(0).as_ref(),
            &insts[..k],
            &opt[..k],
        )?));
    }
    Ok(rows)
}

/// The committed AFGNet models with a price head (ours, [`ModelSpec::PRICE_HEADED`])
/// under `root` on `insts` (N robots each), without repair: exact rollouts up to
/// N = 100 and one network pass per N/10 robots beyond (ten passes); the Q* model also
/// in one pass for all robots (one-shot). Models not committed give no rows.
///
/// # Errors
/// A model that cannot be loaded, and the policies' errors.
pub fn price_headed_rows(
    root: &Path,
    insts: &[Instance],
    opt: &[f64],
) -> Result<Vec<Row>, EvalError> {
    let n = insts.first().map_or(0, Instance::num_robots);
    let mut rows = Vec::new();
    for spec in ModelSpec::PRICE_HEADED {
        let run = spec.run_dir(root);
        if !run.has_weights() {
            continue;
        }
        let trained = if n == spec.trained_at {
            String::new()
        } else {
            format!(", trained at N = {}", spec.trained_at)
        };
        let block = if n >= 500 { n / 10 } else { 1 };
        let mut modes = vec![(
            block,
            match block {
                1 => String::new(),
                b => format!(", network every {b} robots"),
            },
        )];
        if spec.algo == Algo::QStar {
            modes.push((n, ", one-shot (one pass)".to_owned()));
        }
        for (block, mode) in modes {
            let policy = LearnedPolicy::load(&run.weights())?.with_block(block)?;
            let label = spec.label_with(&format!("{mode}{trained}"));
            rows.push(Row::new(evaluate(&label, &policy, insts, opt)?));
        }
    }
    Ok(rows)
}

/// The committed price model's rows (ours, [`PriceSpec::committed`]) under `root` on
/// `insts`: both modes, and from N = 500 on the sequential mode with prices once per
/// N/100 robots too; none while the model is not committed.
///
/// # Errors
/// A model that cannot be loaded, and the policy's errors.
pub fn price_model_rows(
    root: &Path,
    insts: &[Instance],
    opt: &[f64],
) -> Result<Vec<Row>, EvalError> {
    let n = insts.first().map_or(0, Instance::num_robots);
    let [sequential, one_shot] = PriceSpec::committed();
    let blocked = (n >= 500).then(|| sequential.with_block(n / 100));
    let mut rows = Vec::new();
    for spec in [Some(sequential), blocked, Some(one_shot)]
        .into_iter()
        .flatten()
    {
        if spec.model_path(root).exists() {
            let policy = spec.load(root)?;
            rows.push(Row::new(evaluate(&spec.label(), &policy, insts, opt)?));
        }
    }
    Ok(rows)
}

/// A duration with three significant digits and a unit: `12.3 µs`, `4.56 ms`, `7.89 s`.
///
/// # Examples
/// ```
/// use std::time::Duration;
/// use afg_eval::tables::duration;
/// assert_eq!(duration(Duration::from_nanos(12_345)), "12.3 µs");
/// assert_eq!(duration(Duration::from_micros(4_560)), "4.56 ms");
/// assert_eq!(duration(Duration::from_millis(7_890)), "7.89 s");
/// ```
pub fn duration(d: Duration) -> String {
    let s = d.as_secs_f64();
    if s < 1e-3 {
        format!("{:.1} µs", s * 1e6)
    } else if s < 1.0 {
        format!("{:.2} ms", s * 1e3)
    } else {
        format!("{s:.2} s")
    }
}

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
            let reported = match row.model.and_then(|m| paper.welfare_of(&m).map(|w| (m, w))) {
                Some((m, w)) if m == ModelSpec::afgnet_ddqn(n) => {
                    format!("{w} (NS {} %)", paper.afgnet_ddqn_ns_rate)
                }
                Some((_, w)) => format!("{w}"),
                None => "–".into(),
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
        let get = |m: Method| {
            scale
                .rows
                .iter()
                .find(|r| r.model.is_none() && r.summary.method == m.label())
                .map(|r| r.summary.percent_of_opt)
        };
        let (Some(da), Some(greedy), Some(nearest)) =
            (get(Method::Da), get(Method::Greedy), get(Method::Nearest))
        else {
            continue;
        };
        let drl = scale
            .rows
            .iter()
            .find(|r| r.model == Some(ModelSpec::afgnet_ddqn(n)));
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

#[cfg(test)]
mod tests {
    use super::*;

    fn summary(method: &str, pct: f64) -> Summary {
        Summary {
            method: method.to_owned(),
            instances: 3,
            welfare: pct / 2.0,
            percent_of_opt: pct,
            ns_rate_balanced: 50.0,
            ns_rate_selfish: 25.0,
            seconds_per_instance: 2e-6,
        }
    }

    fn scale_60() -> Scale {
        let ddqn = ModelSpec::afgnet_ddqn(60);
        Scale {
            robots: 60,
            rows: vec![
                Row::of_model(ddqn, summary(&ddqn.label(), 98.0)),
                Row::new(summary(Method::Da.label(), 98.9)),
                Row::new(summary(Method::Greedy.label(), 98.5)),
                Row::new(summary(Method::Nearest.label(), 98.6)),
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
        // A row labelled like the paper's model but not marked as one gets no number.
        let mut impostor = scale_60();
        impostor.rows[0].model = None;
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
    fn the_price_headed_rows_name_their_mode_and_scale() {
        let root = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."));
        let labels = |n: usize| -> Vec<String> {
            let insts = crate::dataset::load(root, n).unwrap();
            let insts = &insts[..1];
            let opt = crate::optima(insts).unwrap();
            price_headed_rows(root, insts, &opt)
                .unwrap()
                .into_iter()
                .map(|r| {
                    assert!(r.summary.percent_of_opt > 90.0, "{}", r.summary.method);
                    r.summary.method
                })
                .collect()
        };
        // The three committed models, the Q* one also in one pass.
        let at_60 = labels(60);
        assert_eq!(at_60.len(), 4, "{at_60:?}");
        assert!(at_60.iter().all(|l| !l.contains("trained at")));
        assert_eq!(at_60.iter().filter(|l| l.contains("one-shot")).count(), 1);
        let at_500 = labels(500);
        assert!(at_500.iter().all(|l| l.contains("trained at N = 60")));
        // The price model: both modes, and prices once per N/100 robots from N = 500.
        let insts = crate::dataset::load(root, 500).unwrap();
        let opt = crate::optima(&insts[..1]).unwrap();
        let price = price_model_rows(root, &insts[..1], &opt).unwrap();
        assert_eq!(price.len(), 3);
        assert!(price[1].summary.method.contains("prices every 5 robots"));
        assert_eq!(
            at_500
                .iter()
                .filter(|l| l.contains("network every 50 robots"))
                .count(),
            3
        );
    }

    #[test]
    fn table2_names_the_instances_of_each_row() {
        let scale = Scale {
            robots: 500,
            rows: vec![Row::new(summary(Method::Opt.label(), 100.0))],
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

//! The rows of the tables: every classical method, and the committed models of ours
//! that do not belong to one scale of Table I.

use std::path::Path;

use afg_baseline::Method;
use afg_game::Instance;
use afg_learn::{policy::LearnedPolicy, train::Algo};

use super::Row;
use crate::{EvalError, ModelSpec, PriceSpec, evaluate};

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

#[cfg(test)]
mod tests {
    use super::*;

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
        // The four committed models, the two Q* ones also in one pass.
        let at_60 = labels(60);
        assert_eq!(at_60.len(), 6, "{at_60:?}");
        assert!(at_60.iter().all(|l| !l.contains("trained at")));
        assert_eq!(at_60.iter().filter(|l| l.contains("one-shot")).count(), 2);
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
            4
        );
    }
}

//! Scores of allocations against the exact optimum.

use std::time::Instant;

use afg_baseline::{Allocator, Optimum, percent_of_opt};
use afg_game::{Assignment, Instance, Preference};
use rayon::prelude::*;
use serde::Serialize;

use crate::EvalError;

/// One allocation of one instance, measured against OPT.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct Score {
    /// Welfare of the allocation.
    pub welfare: f64,
    /// Welfare of the exact optimum (in `afg solve`'s rows, what the allocation is
    /// measured against: [`crate::solve::Reference::measure`]; NaN, JSON `null`,
    /// where nothing was).
    #[serde(deserialize_with = "nan_if_null")]
    pub opt_welfare: f64,
    /// `100 · welfare / opt_welfare` ([`percent_of_opt`]); `None` (JSON `null`) when
    /// the optimum's welfare is not positive, where a ratio means nothing.
    pub percent_of_opt: Option<f64>,
    /// Share of robots (0..=1) that would move under the balanced preference.
    pub ns_rate_balanced: f64,
    /// Share of robots (0..=1) that would move under the selfish preference.
    pub ns_rate_selfish: f64,
}

/// A number that JSON may hold as `null` (serde_json's NaN).
fn nan_if_null<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(<Option<f64> as serde::Deserialize>::deserialize(d)?.unwrap_or(f64::NAN))
}

impl Score {
    /// The score of `assignment` on `instance`, whose optimum has welfare `opt_welfare`.
    ///
    /// # Errors
    /// [`EvalError::BeatsOptimum`] (naming `method`) if the welfare exceeds the
    /// optimum's beyond rounding: then the optimum is wrong.
    ///
    /// # Examples
    /// ```
    /// use afg_baseline::{Allocator, Greedy};
    /// use afg_eval::{Score, optimum_welfare};
    /// use afg_game::GeneratorConfig;
    /// let inst = GeneratorConfig::paper(20, 5, 1).generate()?;
    /// let greedy = Greedy.allocate(&inst)?.assignment;
    /// let s = Score::of("greedy", &inst, &greedy, optimum_welfare(&inst)?)?;
    /// assert!(s.percent_of_opt.is_some_and(|p| p <= 100.0 + 1e-9 && p > 80.0));
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn of(
        method: &str,
        instance: &Instance,
        assignment: &Assignment,
        opt_welfare: f64,
    ) -> Result<Score, EvalError> {
        let welfare = instance.welfare(assignment);
        if welfare > opt_welfare + 1e-9 * opt_welfare.abs().max(1.0) {
            return Err(EvalError::BeatsOptimum {
                method: method.to_owned(),
                welfare,
                opt: opt_welfare,
            });
        }
        Ok(Score {
            welfare,
            opt_welfare,
            percent_of_opt: percent_of_opt(welfare, opt_welfare),
            ns_rate_balanced: instance.ns_rate(assignment, Preference::Balanced),
            ns_rate_selfish: instance.ns_rate(assignment, Preference::Selfish),
        })
    }
}

impl Score {
    /// The score of `assignment` measured against nothing: its welfare and NS rates,
    /// `opt_welfare` NaN (JSON `null`) and no percentage.
    pub fn unmeasured(instance: &Instance, assignment: &Assignment) -> Score {
        Score {
            welfare: instance.welfare(assignment),
            opt_welfare: f64::NAN,
            percent_of_opt: None,
            ns_rate_balanced: instance.ns_rate(assignment, Preference::Balanced),
            ns_rate_selfish: instance.ns_rate(assignment, Preference::Selfish),
        }
    }
}

/// Welfare of the exact optimum of `instance`.
///
/// # Errors
/// [`EvalError::Alloc`] if the optimum fails (it does not on valid instances).
pub fn optimum_welfare(instance: &Instance) -> Result<f64, EvalError> {
    Ok(instance.welfare(&Optimum.allocate(instance)?.assignment))
}

/// [`optimum_welfare`] of each instance (instances in parallel, on rayon's pool).
///
/// # Errors
/// As [`optimum_welfare`].
pub fn optima(instances: &[Instance]) -> Result<Vec<f64>, EvalError> {
    instances.par_iter().map(optimum_welfare).collect()
}

/// One allocator on a set of instances: means of the [`Score`]s, NS rates in percent.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    /// The allocator's label.
    pub method: String,
    /// Instances evaluated.
    pub instances: usize,
    /// Mean welfare.
    pub welfare: f64,
    /// Mean of the per-instance % of OPT.
    pub percent_of_opt: f64,
    /// Mean balanced NS_rate, in percent.
    pub ns_rate_balanced: f64,
    /// Mean selfish NS_rate, in percent.
    pub ns_rate_selfish: f64,
    /// Mean wall time of the allocator per instance.
    pub seconds_per_instance: f64,
}

/// Runs `allocator` on every instance and summarises its scores; `opt` holds the
/// optimum's welfare of each instance ([`optima`]).
///
/// Instances run in parallel on rayon's pool (one per core by default;
/// `RAYON_NUM_THREADS=1` runs them one after another). Each instance's wall time is
/// measured on the thread that solves it, and the means are summed in instance
/// order, so the scores do not depend on the number of threads.
///
/// # Errors
/// The allocator's errors, [`EvalError::BeatsOptimum`] (the first instance's in
/// order, when several fail), and [`EvalError::PercentUndefined`] if an instance's
/// optimum has no positive welfare.
///
/// # Examples
/// ```
/// use afg_baseline::{Method, Optimum};
/// use afg_eval::{evaluate, optima};
/// use afg_game::GeneratorConfig;
/// let insts = vec![GeneratorConfig::paper(20, 5, 1).generate()?, GeneratorConfig::paper(20, 5, 2).generate()?];
/// let opt = optima(&insts)?;
/// let s = evaluate(Method::Opt.label(), &Optimum, &insts, &opt)?;
/// assert_eq!((s.instances, s.percent_of_opt), (2, 100.0));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn evaluate(
    label: &str,
    allocator: &dyn Allocator,
    instances: &[Instance],
    opt: &[f64],
) -> Result<Summary, EvalError> {
    let runs = instances
        .par_iter()
        .zip(opt)
        .map(|(inst, &o)| {
            let start = Instant::now();
            let a = allocator.allocate(inst)?.assignment;
            let secs = start.elapsed().as_secs_f64();
            Ok((Score::of(label, inst, &a, o)?, secs))
        })
        .collect::<Result<Vec<_>, EvalError>>()?;
    let (mut welfare, mut pct, mut nsb, mut nss, mut secs) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (s, t) in &runs {
        welfare += s.welfare;
        pct += s.percent_of_opt.ok_or(EvalError::PercentUndefined)?;
        nsb += s.ns_rate_balanced;
        nss += s.ns_rate_selfish;
        secs += t;
    }
    let k = runs.len() as f64;
    Ok(Summary {
        method: label.to_owned(),
        instances: runs.len(),
        welfare: welfare / k,
        percent_of_opt: pct / k,
        ns_rate_balanced: 100.0 * nsb / k,
        ns_rate_selfish: 100.0 * nss / k,
        seconds_per_instance: secs / k,
    })
}

#[cfg(test)]
mod tests {
    use afg_baseline::Method;
    use afg_game::GeneratorConfig;

    use super::*;

    /// `evaluate` on a pool of `threads` threads.
    fn on_threads(threads: usize, method: Method, insts: &[Instance], opt: &[f64]) -> Summary {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| evaluate(method.label(), method.allocator(3).as_ref(), insts, opt))
            .unwrap()
    }

    #[test]
    fn scores_do_not_depend_on_the_number_of_threads() {
        let insts: Vec<Instance> = (0..12)
            .map(|s| GeneratorConfig::paper(30, 4, s).generate().unwrap())
            .collect();
        let opt = optima(&insts).unwrap();
        for method in [Method::Greedy, Method::Random, Method::DaDecentralised] {
            let one = on_threads(1, method, &insts, &opt);
            let four = on_threads(4, method, &insts, &opt);
            assert_eq!(
                (one.instances, one.welfare, one.percent_of_opt),
                (four.instances, four.welfare, four.percent_of_opt)
            );
            assert_eq!(
                (one.ns_rate_balanced, one.ns_rate_selfish),
                (four.ns_rate_balanced, four.ns_rate_selfish)
            );
            // The means are those of the instances taken one by one.
            let alloc = method.allocator(3);
            let by_hand: f64 = insts
                .iter()
                .map(|inst| inst.welfare(&alloc.allocate(inst).unwrap().assignment))
                .sum::<f64>()
                / insts.len() as f64;
            assert!((one.welfare - by_hand).abs() < 1e-9);
        }
        assert_eq!(
            on_threads(3, Method::Opt, &insts, &opt).percent_of_opt,
            100.0
        );
    }
}

//! One allocator on a set of instances, instance by instance (`afg solve`): each
//! instance's score and the means.

use afg_baseline::{AllocStats, Allocator, TeamOptimum};
use afg_game::{Assignment, Instance, Preference};
use serde::Serialize;

use crate::{EvalError, Score, optimum_welfare};

/// What a row's "% of OPT" is measured against.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Against {
    /// The exact optimum, its search stopped within `time_limit` seconds on a team game
    /// (`None`: until proven; the paper's game is always solved exactly); where it
    /// stops unproven, the share is of its certified bound.
    Optimum {
        /// Seconds per instance, finite and positive.
        time_limit: Option<f64>,
    },
    /// Nothing: the welfare alone, no optimum computed and no % of OPT.
    Nothing,
}

impl Default for Against {
    fn default() -> Self {
        Against::Optimum { time_limit: None }
    }
}

impl Against {
    /// The exact optimum stopped within `seconds` on a team game, the limit checked
    /// now (before any work) by the exact solver's own rule.
    ///
    /// # Errors
    /// [`EvalError::Alloc`] where `seconds` is not finite and positive.
    ///
    /// # Examples
    /// ```
    /// use afg_eval::solve::Against;
    /// assert!(Against::optimum_within(10.0).is_ok());
    /// assert!(Against::optimum_within(0.0).is_err());
    /// ```
    pub fn optimum_within(seconds: f64) -> Result<Against, EvalError> {
        TeamOptimum::with_time_limit(seconds)?;
        Ok(Against::Optimum {
            time_limit: Some(seconds),
        })
    }
}

/// What a row was measured against: the exact solver's best welfare, its certified
/// bound, and whether that welfare is proven optimal. Where it is not, "% of OPT" is
/// of the bound: a lower bound on the true share.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Reference {
    /// The best welfare the exact solver found.
    pub welfare: f64,
    /// Its certified upper bound on every assignment's welfare.
    pub bound: f64,
    /// Whether `welfare` is proven optimal (then `bound` equals it).
    pub proven: bool,
}

impl Reference {
    /// The exact solver's answer on `instance` within `time_limit` seconds (see
    /// [`Against::Optimum`]).
    ///
    /// # Errors
    /// [`EvalError::Alloc`] for a time limit that is not finite and positive.
    ///
    /// # Examples
    /// ```
    /// use afg_eval::solve::Reference;
    /// use afg_game::GeneratorConfig;
    /// let mut cfg = GeneratorConfig::paper(40, 5, 3);
    /// cfg.min_team = Some(afg_game::CountRange { min: 8, max: 16 });
    /// let inst = cfg.generate()?;
    /// let exact = Reference::of(&inst, None)?;
    /// assert!(exact.proven && exact.bound == exact.welfare);
    /// let root = Reference::of(&inst, Some(1e-9))?;
    /// assert!(root.bound >= exact.welfare - 1e-9 && root.welfare <= exact.welfare + 1e-9);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn of(instance: &Instance, time_limit: Option<f64>) -> Result<Reference, EvalError> {
        if !instance.has_teams() {
            let welfare = optimum_welfare(instance)?;
            return Ok(Reference {
                welfare,
                bound: welfare,
                proven: true,
            });
        }
        let solver = match time_limit {
            Some(seconds) => TeamOptimum::with_time_limit(seconds)?,
            None => TeamOptimum::default(),
        };
        let found = solver.solve(instance)?;
        Ok(Reference {
            welfare: found.welfare,
            bound: found.bound,
            proven: found.proven,
        })
    }

    /// What "% of OPT" divides by: the optimum where proven, the bound otherwise.
    pub fn measure(&self) -> f64 {
        if self.proven {
            self.welfare
        } else {
            self.bound
        }
    }
}

/// One instance's result.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    /// The allocation against OPT (its `opt_welfare` is the reference's
    /// [`Reference::measure`]: the bound where the optimum is not proven; NaN, printed
    /// `null`, and no percentage where [`Against::Nothing`]).
    #[serde(flatten)]
    pub score: Score,
    /// What the allocation was measured against (`None` with [`Against::Nothing`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reference: Option<Reference>,
    /// What the allocator reported.
    pub stats: AllocStats,
    /// An exact method's certified gap `(bound − welfare) / |welfare|` (0 when proven
    /// optimal; the bound is in `stats`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gap: Option<f64>,
}

impl Row {
    /// Runs `method` on `instance` and measures it `against` the optimum: the row and
    /// the method's assignment. An exact method that reports a bound (the optimum
    /// under a time limit) is its own reference: its welfare against its bound.
    ///
    /// # Errors
    /// The allocators' errors, or [`EvalError::BeatsOptimum`].
    pub fn compute(
        instance: &Instance,
        method: &dyn Allocator,
        against: Against,
    ) -> Result<(Row, Assignment), EvalError> {
        let out = method.allocate(instance)?;
        let welfare = instance.welfare(&out.assignment);
        let gap = out.stats.gap(welfare);
        let reference = match (out.stats.bound, against) {
            (Some(bound), _) => Some(Reference {
                welfare,
                bound,
                proven: gap == Some(0.0),
            }),
            (None, Against::Nothing) => None,
            (None, Against::Optimum { time_limit }) => Some(Reference::of(instance, time_limit)?),
        };
        let score = match reference {
            Some(r) => Score::of("the allocation", instance, &out.assignment, r.measure())?,
            None => Score::unmeasured(instance, &out.assignment),
        };
        let row = Row {
            score,
            reference,
            stats: out.stats,
            gap,
        };
        Ok((row, out.assignment))
    }

    /// The JSON line of `assignment` (format "afg-assignment") with a summary of this
    /// row: welfare, % of OPT, coalition sizes, stability and NS rates.
    pub fn assignment_line(
        &self,
        method: &str,
        instance: &Instance,
        assignment: &Assignment,
    ) -> String {
        assignment.to_json_with_summary(Some(serde_json::json!({
            "method": method,
            "welfare": self.score.welfare,
            "opt_welfare": self.score.opt_welfare,
            "percent_of_opt": self.score.percent_of_opt,
            "reference": self.reference,
            "coalition_sizes": assignment.sizes(),
            "stable_balanced": instance.is_stable(assignment, Preference::Balanced),
            "ns_rate_balanced": self.score.ns_rate_balanced,
            "ns_rate_selfish": self.score.ns_rate_selfish,
        })))
    }
}

/// The rows of one allocator on a set of instances, and their means.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// The allocator.
    pub method: String,
    /// Where the instances came from.
    pub source: String,
    /// Instances solved.
    pub instances: usize,
    /// Means over the rows.
    pub mean: Mean,
    /// One per instance.
    pub rows: Vec<Row>,
}

/// Means of a [`Report`]'s rows (NS rates as shares in 0..=1, as in [`Score`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Mean {
    /// Welfare.
    pub welfare: f64,
    /// OPT's welfare.
    pub opt_welfare: f64,
    /// Mean of the per-instance % of OPT; `None` if one of them is undefined.
    pub percent_of_opt: Option<f64>,
    /// Balanced NS rate.
    pub ns_rate_balanced: f64,
    /// Selfish NS rate.
    pub ns_rate_selfish: f64,
    /// [`AllocStats::iterations`].
    pub iterations: f64,
    /// [`AllocStats::rounds`].
    pub rounds: f64,
    /// [`AllocStats::messages`].
    pub messages: f64,
    /// Wall time per instance, seconds.
    pub seconds: f64,
    /// The largest certified gap of an exact method (`None` for the others).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_gap: Option<f64>,
}

impl Report {
    /// The report of `rows` (at least one).
    ///
    /// # Errors
    /// [`EvalError::NoInstances`] if `rows` is empty.
    pub fn new(method: String, source: String, rows: Vec<Row>) -> Result<Report, EvalError> {
        if rows.is_empty() {
            return Err(EvalError::NoInstances);
        }
        let k = rows.len() as f64;
        let mean = |f: &dyn Fn(&Row) -> f64| rows.iter().map(f).sum::<f64>() / k;
        let mean = Mean {
            welfare: mean(&|r| r.score.welfare),
            opt_welfare: mean(&|r| r.score.opt_welfare),
            percent_of_opt: rows
                .iter()
                .map(|r| r.score.percent_of_opt)
                .sum::<Option<f64>>()
                .map(|total| total / k),
            ns_rate_balanced: mean(&|r| r.score.ns_rate_balanced),
            ns_rate_selfish: mean(&|r| r.score.ns_rate_selfish),
            iterations: mean(&|r| r.stats.iterations as f64),
            rounds: mean(&|r| r.stats.rounds as f64),
            messages: mean(&|r| r.stats.messages as f64),
            seconds: mean(&|r| r.stats.wall_time.as_secs_f64()),
            max_gap: rows
                .iter()
                .map(|r| r.gap)
                .sum::<Option<f64>>()
                .map(|_| rows.iter().filter_map(|r| r.gap).fold(0.0, f64::max)),
        };
        Ok(Report {
            method,
            source,
            instances: rows.len(),
            mean,
            rows,
        })
    }
}

/// A % of OPT as printed: two decimals, or why there is none.
pub fn percent_text(percent: Option<f64>) -> String {
    percent.map_or_else(
        || "undefined (OPT's welfare <= 0)".to_owned(),
        |p| format!("{p:.2}"),
    )
}

/// The report as `afg solve` prints it: the means, one per line.
impl std::fmt::Display for Report {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (m, k) = (&self.mean, self.instances);
        let plural = if k == 1 { "" } else { "s" };
        writeln!(
            f,
            "{} on {} ({k} instance{plural})",
            self.method, self.source
        )?;
        match m.max_gap {
            // The exact method itself: its welfare against its own proven bound.
            Some(gap) => {
                let bound = self.rows.iter().filter_map(|r| r.stats.bound).sum::<f64>() / k as f64;
                let proven = self.rows.iter().filter(|r| r.gap == Some(0.0)).count();
                writeln!(f, "  welfare           {:>12.3}", m.welfare)?;
                writeln!(
                    f,
                    "  bound             {bound:>12.3}   (proven upper bound)"
                )?;
                writeln!(
                    f,
                    "  gap               {:>11.4} %   (largest; {proven} of {k} proven optimal)",
                    100.0 * gap
                )?;
            }
            None if self.rows.iter().any(|r| r.reference.is_none()) => {
                writeln!(
                    f,
                    "  welfare           {:>12.3}   (not measured against the optimum)",
                    m.welfare
                )?;
            }
            None => {
                let unproven = (self.rows.iter())
                    .filter(|r| r.reference.is_some_and(|x| !x.proven))
                    .count();
                let opt = if unproven > 0 {
                    "OPT or its bound"
                } else {
                    "OPT"
                };
                writeln!(
                    f,
                    "  welfare           {:>12.3}   ({opt} {:.3})",
                    m.welfare, m.opt_welfare
                )?;
                writeln!(
                    f,
                    "  % of OPT          {:>12}",
                    percent_text(m.percent_of_opt)
                )?;
                if unproven > 0 {
                    writeln!(
                        f,
                        "                    (of the certified bound on {unproven} of {k}: the optimum was not proven in time)"
                    )?;
                }
            }
        }
        writeln!(
            f,
            "  NS_rate balanced  {:>11.1} %",
            100.0 * m.ns_rate_balanced
        )?;
        writeln!(
            f,
            "  NS_rate selfish   {:>11.1} %",
            100.0 * m.ns_rate_selfish
        )?;
        writeln!(f, "  iterations        {:>12.1}", m.iterations)?;
        writeln!(f, "  rounds            {:>12.1}", m.rounds)?;
        if m.messages > 0.0 {
            writeln!(f, "  messages          {:>12.0}", m.messages)?;
        }
        writeln!(f, "  time / instance   {:>10.3} ms", 1e3 * m.seconds)?;
        if k > 1 {
            writeln!(f, "  (means over instances; --json for each one)")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use afg_baseline::{Greedy, Optimum};
    use afg_game::GeneratorConfig;

    use super::*;

    /// Where the optimum is not proven in time, the share is of its bound, said so; the
    /// exact method stopped early is below 100 % by its gap.
    #[test]
    fn an_unproven_optimum_measures_against_its_bound() {
        let mut cfg = GeneratorConfig::paper(100, 10, 1);
        cfg.min_team = Some(afg_game::CountRange { min: 10, max: 20 });
        let inst = cfg.generate().unwrap();
        let rushed = Against::Optimum {
            time_limit: Some(1e-9),
        };
        let (row, _) = Row::compute(&inst, &afg_baseline::Nearest, rushed).unwrap();
        let reference = row.reference.unwrap();
        assert!(!reference.proven && reference.bound > reference.welfare);
        let percent = 100.0 * row.score.welfare / reference.bound;
        assert_eq!(row.score.percent_of_opt, Some(percent));
        let text = Report::new("nearest".into(), "here".into(), vec![row])
            .unwrap()
            .to_string();
        assert!(text.contains("of the certified bound on 1 of 1"), "{text}");
        let cut = afg_baseline::TeamOptimum::with_time_limit(1e-9).unwrap();
        let (row, _) = Row::compute(&inst, &cut, Against::default()).unwrap();
        let gap = row.gap.unwrap();
        assert!(gap > 0.0);
        let percent = row.score.percent_of_opt.unwrap();
        assert!(
            (percent - 100.0 / (1.0 + gap)).abs() < 1e-9,
            "{percent} {gap}"
        );
    }

    #[test]
    fn the_means_are_those_of_the_rows() {
        let insts: Vec<Instance> = (0..3)
            .map(|s| GeneratorConfig::paper(15, 3, s).generate().unwrap())
            .collect();
        let rows: Vec<Row> = insts
            .iter()
            .map(|i| Row::compute(i, &Greedy, Against::default()).unwrap().0)
            .collect();
        let by_hand = rows.iter().map(|r| r.score.welfare).sum::<f64>() / 3.0;
        let report = Report::new("greedy".into(), "here".into(), rows).unwrap();
        assert_eq!(report.instances, 3);
        assert!((report.mean.welfare - by_hand).abs() < 1e-12);
        let text = report.to_string();
        assert!(text.starts_with("greedy on here (3 instances)\n"), "{text}");
        let welfare = format!("welfare           {:>12.3}", by_hand);
        assert!(
            text.contains(&welfare) && !text.contains("messages"),
            "{text}"
        );
        assert!(report.mean.percent_of_opt.unwrap() <= 100.0 + 1e-9);
        let (opt, _) = Row::compute(&insts[0], &Optimum, Against::default()).unwrap();
        assert_eq!(opt.score.percent_of_opt, Some(100.0));
        // Measured against nothing: no optimum, no percentage, said so.
        let (alone, _) = Row::compute(&insts[0], &Greedy, Against::Nothing).unwrap();
        assert!(alone.reference.is_none() && alone.score.percent_of_opt.is_none());
        let text = Report::new("greedy".into(), "here".into(), vec![alone])
            .unwrap()
            .to_string();
        assert!(text.contains("not measured against the optimum"), "{text}");
        assert!(matches!(
            Report::new("x".into(), "y".into(), Vec::new()),
            Err(EvalError::NoInstances)
        ));
    }
}

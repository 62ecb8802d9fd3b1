//! The scheduler: an order of the tasks, decoded into teams and routes, improved by
//! simulated annealing on the order (move a task, swap two, move a block) under a time
//! limit or a number of steps. Seeded and, for a number of steps, deterministic.

use std::time::{Duration, Instant};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::anneal::{Plan, anneal};
use crate::decode::Decoder;
use crate::{Evaluation, Schedule, ScheduleError, ScheduleInstance};

/// How long and how the scheduler searches.
///
/// # Examples
/// ```
/// use afg_schedule::{SolveOptions, ScheduleInstance};
/// let inst = ScheduleInstance::from_json(r#"{"speed":1,"max_wait":10,"depots":[[0,0]],
///   "robots":[{"x":0,"y":0,"depot":0},{"x":0,"y":0,"depot":0}],
///   "tasks":[{"x":0,"y":1,"min_team":2,"duration":1},{"x":1,"y":0,"min_team":1,"duration":1},
///            {"x":-1,"y":0,"min_team":1,"duration":1}]}"#)?;
/// let found = inst.solve(&SolveOptions { steps: Some(2_000), ..SolveOptions::default() })?;
/// // Together to task 0 (t = 1, done at 2), then one robot to each side task.
/// assert!((found.makespan() - (2.0 + 2f64.sqrt() + 2.0)).abs() < 1e-9);
/// assert!(inst.evaluate(&found.schedule)?.is_valid());
/// # Ok::<(), afg_schedule::ScheduleError>(())
/// ```
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SolveOptions {
    /// Stop after this many seconds (the default when neither limit is set: 1 s).
    pub time_limit: Option<f64>,
    /// Stop after this many search steps (deterministic for a seed).
    pub steps: Option<u64>,
    /// The random seed.
    pub seed: u64,
    /// The longest any robot may wait for its team (default: the instance's `max_wait`).
    pub max_wait: Option<f64>,
    /// A schedule to improve (a plan of one's own, or an earlier search's): its tasks in
    /// the order they start are one of the orders the search may start from, and where
    /// it is valid under the `max_wait` asked for and nothing found is better, it is
    /// what comes back.
    pub start: Option<Schedule>,
}

/// What the scheduler found.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Solved {
    /// The schedule: one route per robot.
    pub schedule: Schedule,
    /// The schedule played by the evaluator under the `max_wait` asked for (valid).
    pub run: Evaluation,
    /// The order of the tasks it was decoded from (where the start given comes back,
    /// its tasks in the order they start).
    pub order: Vec<usize>,
    /// Search steps taken.
    pub steps: u64,
    /// Seconds spent.
    pub seconds: f64,
}

impl Solved {
    /// The schedule's makespan (the evaluator's).
    pub fn makespan(&self) -> f64 {
        self.run.makespan
    }
}

impl ScheduleInstance {
    /// Plans a whole schedule (see [`SolveOptions`]); every schedule it returns is valid
    /// under the `max_wait` asked for.
    pub fn solve(&self, options: &SolveOptions) -> Result<Solved, ScheduleError> {
        let max_wait = options.max_wait.unwrap_or(self.max_wait);
        if max_wait.is_nan() || max_wait <= 0.0 {
            return Err(ScheduleError::Setting(format!(
                "max_wait must be above 0, not {max_wait}"
            )));
        }
        if let Some(t) = options.time_limit.filter(|t| !(t.is_finite() && *t > 0.0)) {
            return Err(ScheduleError::Setting(format!(
                "the time limit must be a finite number of seconds above 0, not {t}"
            )));
        }
        let clock = Instant::now();
        let given = match &options.start {
            Some(schedule) => Some((schedule, self.evaluate_with(schedule, max_wait)?)),
            None => None,
        };
        let given_order = given.as_ref().map(|(_, run)| by_start(run));
        let decoder = Decoder::new(self, max_wait);
        let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
        let mut plan = first_plan(self, &decoder, &mut rng, given_order.clone());
        let limit = match (options.time_limit, options.steps) {
            (None, None) => Some(Duration::from_secs(1)),
            (t, _) => t.map(Duration::from_secs_f64),
        };
        // What is left after the search (a decode, the routes, the evaluator's replay)
        // costs less than the five decodes of the first plan: keep that much back.
        let reserve = clock.elapsed();
        let deadline = limit.map(|l| clock + l.saturating_sub(reserve));
        let steps = anneal(&mut plan, &mut rng, deadline, options.steps);
        if let (Some((schedule, run)), Some(order)) = (given, given_order)
            && run.is_valid()
            && (plan.cost().overwait > 0.0 || run.makespan <= plan.cost().makespan)
        {
            return Ok(Solved {
                schedule: schedule.clone(),
                run,
                order,
                steps,
                seconds: clock.elapsed().as_secs_f64(),
            });
        }
        if plan.cost().overwait > 0.0 {
            return Err(ScheduleError::Setting(format!(
                "found no schedule whose teams all gather within max_wait {max_wait} in the search given \
                 (the best keeps robots waiting {:.3} beyond it in all): allow longer waits or search longer",
                plan.cost().overwait
            )));
        }
        let routes = decoder.routes(&plan.order);
        let schedule = Schedule { routes };
        let run = self.evaluate_with(&schedule, max_wait)?;
        // The decoder's times are the evaluator's; a difference would be a bug, never a result.
        if !run.is_valid()
            || (run.makespan - plan.cost().makespan).abs() > 1e-9 * run.makespan.max(1.0)
        {
            return Err(ScheduleError::Setting(format!(
                "afg's scheduler and its evaluator disagree on this instance (makespan {} against {}): please report it",
                plan.cost().makespan,
                run.makespan
            )));
        }
        Ok(Solved {
            schedule,
            run,
            order: plan.order,
            steps,
            seconds: clock.elapsed().as_secs_f64(),
        })
    }
}

/// A schedule's tasks in the order they start (ties by task id).
fn by_start(run: &Evaluation) -> Vec<usize> {
    let mut order: Vec<usize> = (0..run.start.len()).collect();
    order.sort_by(|&a, &b| run.start[a].total_cmp(&run.start[b]).then(a.cmp(&b)));
    order
}

/// The best of a few orders: nearest task first from the depot, by distance, shuffles,
/// and the order of a schedule given to start from.
fn first_plan<'a>(
    inst: &ScheduleInstance,
    decoder: &'a Decoder,
    rng: &mut ChaCha8Rng,
    given: Option<Vec<usize>>,
) -> Plan<'a> {
    let m = inst.num_tasks();
    let home = [inst.depots[0][0], inst.depots[0][1]];
    let far = |j: usize| (inst.tasks[j].x - home[0]).hypot(inst.tasks[j].y - home[1]);
    let mut by_distance: Vec<usize> = (0..m).collect();
    by_distance.sort_by(|&a, &b| far(a).total_cmp(&far(b)));
    let mut candidates = vec![by_distance];
    for _ in 0..4 {
        let mut o: Vec<usize> = (0..m).collect();
        for k in (1..m).rev() {
            o.swap(k, rng.random_range(0..=k));
        }
        candidates.push(o);
    }
    candidates.extend(given);
    candidates
        .into_iter()
        .map(|o| Plan::new(decoder, o))
        .reduce(|a, b| if b.cost().better_than(a.cost()) { b } else { a })
        .expect("five candidates")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Family, Generate};

    /// The order of a schedule given to start from is among the first plans: the plan
    /// the search starts from is no worse than that order decoded.
    #[test]
    fn the_first_plan_is_no_worse_than_a_given_order() {
        for seed in 0..10 {
            let inst = Generate {
                family: Family::Dcmrta,
                robots: 8,
                tasks: 20,
                seed,
            }
            .instance()
            .unwrap();
            let decoder = Decoder::new(&inst, inst.max_wait);
            let searched = inst
                .solve(&SolveOptions {
                    steps: Some(5_000),
                    seed,
                    ..SolveOptions::default()
                })
                .unwrap()
                .order;
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let first = first_plan(&inst, &decoder, &mut rng, Some(searched.clone())).cost();
            let given = Plan::new(&decoder, searched).cost();
            assert!(!given.better_than(first), "seed {seed}");
        }
    }
}

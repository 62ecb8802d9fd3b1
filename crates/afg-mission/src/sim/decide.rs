//! Decisions: the game of the current state, the allocator, and the decision landing.

use std::collections::HashMap;
use std::time::Instant;

use afg_baseline::{CentralisedDa, Optimum, Plays, check_game};
use afg_game::{Assignment, Instance, RobotId, TaskId};

use super::{Latency, Pending, Replan, Sim, TraceEvent, mission_game};
use crate::MissionError;

impl Sim<'_, '_> {
    /// A decision on the current state: the living robots at their positions, the open
    /// tasks. It lands now, or after the latency.
    pub(super) fn decide(&mut self) -> Result<(), MissionError> {
        let alive: Vec<usize> = (0..self.robots.len())
            .filter(|&i| self.robots[i].alive)
            .collect();
        let open: Vec<usize> = (0..self.tasks.len())
            .filter(|&j| self.tasks[j].open)
            .collect();
        if alive.is_empty() || open.is_empty() {
            return Ok(());
        }
        let game = self.game(&alive, &open)?;
        let places = self.places(&alive, &open);
        let start = Instant::now();
        let (mut assignment, gap) = self.plan(&game, &open, &places).map_err(|e| match e {
            MissionError::Alloc(source) => MissionError::Decision {
                time: self.now,
                robots: alive.len(),
                tasks: open.len(),
                source,
            },
            other => other,
        })?;
        let compute_s = start.elapsed().as_secs_f64();
        self.keep_places(&game, &places, &mut assignment);
        self.decisions += 1;
        self.pairs += (alive.len() * open.len()) as u64;
        self.compute.push(compute_s);
        self.gaps.extend(gap);
        let tasks = alive
            .iter()
            .zip(assignment.tasks())
            .map(|(&i, t)| (i, t.map(|j| open[j.index()])))
            .collect();
        let delay = match self.options.latency {
            Latency::None => 0.0,
            Latency::Fixed { delay } => delay,
            Latency::Measured { factor } => compute_s * factor,
        };
        self.pending = Some(Pending {
            ready: self.now + delay,
            asked: self.now,
            tasks,
            compute_s,
            gap,
        });
        self.decided = true;
        if delay == 0.0 {
            self.land();
        }
        Ok(())
    }

    /// The policies around the allocator: with commitment, robots at work keep their
    /// task (a robot the allocator put in a task they leave no room in idles); with
    /// hysteresis θ, a travelling robot keeps its task unless the new one scores more
    /// than θ above it (balanced scores in the decision's game).
    fn keep_places(
        &self,
        game: &Instance,
        places: &[Option<(TaskId, bool)>],
        assignment: &mut Assignment,
    ) {
        if self.options.commit {
            for (k, place) in places.iter().enumerate() {
                if let Some((task, true)) = *place {
                    assignment.set(RobotId(k as u32), Some(task));
                }
            }
            for j in game.task_ids() {
                let mut over = assignment.size(j).saturating_sub(game.capacity(j));
                for (k, &place) in places.iter().enumerate() {
                    let robot = RobotId(k as u32);
                    if over > 0 && assignment.task_of(robot) == Some(j) && place != Some((j, true))
                    {
                        assignment.set(robot, None);
                        over -= 1;
                    }
                }
            }
        }
        let Some(threshold) = self.options.hysteresis else {
            return;
        };
        for (k, &place) in places.iter().enumerate() {
            let robot = RobotId(k as u32);
            let (Some((old, false)), Some(new)) = (place, assignment.task_of(robot)) else {
                continue;
            };
            let balanced = afg_game::Preference::Balanced;
            let gain = game.score(assignment, robot, new, balanced)
                - game.score(assignment, robot, old, balanced);
            if new != old && gain <= threshold && assignment.has_room(game, robot, old) {
                assignment.set(robot, Some(old));
            }
        }
    }

    /// Each robot of `alive`: its task as a column of the game of `open` (if still
    /// open), and whether it is there.
    fn places(&self, alive: &[usize], open: &[usize]) -> Vec<Option<(TaskId, bool)>> {
        let column: HashMap<usize, usize> = open.iter().enumerate().map(|(k, &j)| (j, k)).collect();
        alive
            .iter()
            .map(|&i| {
                let r = &self.robots[i];
                let task = r.task.and_then(|j| column.get(&j))?;
                Some((TaskId(*task as u32), r.there))
            })
            .collect()
    }

    /// The game of the living robots `alive` (at their positions now) and the open tasks
    /// `open`: GRAPE's game where the mission allows idling, or where the open tasks
    /// cannot hold every robot (the extra robots then idle).
    fn game(&self, alive: &[usize], open: &[usize]) -> Result<Instance, MissionError> {
        let positions = alive.iter().map(|&i| self.position(i)).collect();
        mission_game(&self.mission, alive, positions, open)
    }

    /// The assignment of `game` by the replanning rule, and the certified gap of an
    /// allocator that reports a bound (the exact team solver).
    fn plan(
        &mut self,
        game: &Instance,
        open: &[usize],
        places: &[Option<(TaskId, bool)>],
    ) -> Result<(Assignment, Option<f64>), MissionError> {
        let Some(replan) = self.replan else {
            return Err(MissionError::Invalid(
                "decisions are made by the environment's agents".into(),
            ));
        };
        match replan {
            Replan::Scratch(allocator) => {
                let out = allocator.allocate(game)?;
                let welfare = game.welfare(&out.assignment);
                let gap = out.stats.gap(welfare);
                Ok((out.assignment, gap))
            }
            Replan::Warm { first, .. } if !self.decided => {
                Ok((first.allocate(game)?.assignment, None))
            }
            Replan::Warm { preference, .. } => {
                let da = CentralisedDa::new(preference);
                check_game(game, &da, Plays::Counts)?;
                let mut a = Assignment::unassigned(game.num_robots(), game.num_tasks());
                for (k, place) in places.iter().enumerate() {
                    let robot = RobotId(k as u32);
                    if let Some((task, _)) = *place
                        && a.has_room(game, robot, task)
                    {
                        a.set(robot, Some(task));
                    }
                }
                da.improve(game, &mut a);
                Ok((a, None))
            }
            Replan::Decentralised(_) => Err(MissionError::Invalid(
                "a decentralised method makes no central decision".into(),
            )),
            Replan::WarmOpt => {
                if game.has_teams() {
                    return Err(MissionError::Invalid(
                        "the warm optimum (--warm) reuses a flow's prices, which a team game has not: run opt without --warm".into(),
                    ));
                }
                let (a, prices) = if self.decided {
                    let start: Vec<f64> = open
                        .iter()
                        .enumerate()
                        .map(|(k, j)| {
                            let new = || Optimum::start_price(game, TaskId(k as u32));
                            self.prices.get(j).copied().unwrap_or_else(new)
                        })
                        .collect();
                    Optimum.with_prices_from(game, &start)?
                } else {
                    Optimum.with_prices(game)
                };
                self.prices = open.iter().copied().zip(prices).collect();
                Ok((a, None))
            }
        }
    }

    /// The pending decision takes effect: each living robot heads for its task (if still
    /// open) or stops.
    pub(super) fn land(&mut self) {
        let Some(p) = self.pending.take() else {
            return;
        };
        for &(i, task) in &p.tasks {
            if !self.robots[i].alive {
                continue;
            }
            match task.filter(|&j| self.tasks[j].open) {
                Some(j) => self.send(i, j),
                None if self.robots[i].task.is_some() => self.stop(i),
                None => {}
            }
        }
        self.log_decision(p.asked, p.compute_s, p.gap);
    }

    /// Logs where every robot is heading now, decided at `asked` in `compute_s` (with
    /// the exact solver's `gap`, if it decided).
    pub(super) fn log_decision(&mut self, asked: f64, compute_s: f64, gap: Option<f64>) {
        if !self.options.trace {
            return;
        }
        let tasks = (self.robots.iter())
            .map(|r| r.task.map_or(-1, |j| j as i64))
            .collect();
        let positions = (0..self.robots.len())
            .map(|i| {
                let p = self.position(i);
                [p.x, p.y]
            })
            .collect();
        self.trace.push(TraceEvent::Decision {
            time: self.now,
            asked,
            tasks,
            positions,
            compute_s,
            gap,
        });
    }
}

//! A certified lower bound on the makespan.
//!
//! Every robot is busy until it is back: working, driving or waiting. Summed over the
//! robots, the makespan times N is at least the work every team must do (each task's
//! fewest robots times its duration) plus the least total driving that could bring those
//! teams in and the robots home. That least driving is a transportation problem: every
//! task sends as many robots on as it receives, each robot leaves its start once and
//! reaches its depot once, and no task feeds itself. Its optimum, found exactly by
//! successive shortest paths, lies below the driving of any schedule (it drops only
//! the order in time). Some of that order comes back as one limit per two tasks: a
//! robot that goes from a to b arrives after a is done, so no robot goes from b to a,
//! and at most min(team of a, team of b) go between them at all. Those limits are
//! priced into the driving (a Lagrangian relaxation, its prices set by subgradient
//! rounds; every round is itself a bound). With skills the same holds for the robots
//! that hold each skill alone: they must bring every unit of it that the tasks
//! require. The bound is the largest of these loads and the longest single trip (a
//! round trip to one task and its duration).

use serde::{Deserialize, Serialize};

use crate::{Place, ScheduleInstance};

/// The most tasks for which the bound solves its transportation problem (about a second
/// at 2 000 tasks on one core).
pub const TRANSPORT_LIMIT: usize = 2_000;

/// The most subgradient rounds that price the one-way limit between each two tasks.
const ONE_WAY_ROUNDS: usize = 60;

/// What those rounds may cost, as units shipped × nodes² summed over them: all 60 (about
/// 0.15 s) on DCMRTA's 50 tasks, about 15 on 100 tasks, none on 500.
const ONE_WAY_WORK: usize = 200_000_000;

/// The lower bound and its parts.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Bound {
    /// No schedule of the instance finishes earlier.
    pub makespan: f64,
    /// The load bound: (work + least driving time) / N.
    pub load: f64,
    /// Per skill, the load bound of the robots that hold it (empty without skills).
    pub skill_loads: Vec<f64>,
    /// The longest single trip: out to a task, its duration, and back.
    pub trip: f64,
    /// The least total driving time of the transportation problem.
    pub driving: f64,
    /// The total work: Σ_j (fewest robots of j) × duration_j.
    pub work: f64,
}

impl Bound {
    /// The certified gap of a schedule with this makespan: how far above the optimum it
    /// can be, as a share of its makespan (Gurobi's MIPGap for a minimisation).
    ///
    /// # Examples
    /// ```
    /// let bound = afg_schedule::Bound { makespan: 9.0, load: 9.0, skill_loads: vec![], trip: 4.0, driving: 3.0, work: 15.0 };
    /// assert_eq!(bound.gap(10.0), 0.1);
    /// ```
    pub fn gap(&self, makespan: f64) -> f64 {
        ((makespan - self.makespan) / makespan.max(1e-12)).max(0.0)
    }
}

impl ScheduleInstance {
    /// The fewest robots that can make up task j's team: its `min_team`, enough robots
    /// to hold each skill it requires (counting the most any one robot holds), and
    /// enough to hold all the units it requires together (counting the most useful
    /// units any one robot holds: one robot per skill where each holds one).
    ///
    /// # Examples
    /// ```
    /// use afg_schedule::ScheduleInstance;
    /// let inst = ScheduleInstance::from_json(r#"{"speed":1,"max_wait":10,"skills":3,"depots":[[0,0]],
    ///   "robots":[{"x":0,"y":0,"depot":0,"skills":[1,0,0]},{"x":0,"y":0,"depot":0,"skills":[0,1,0]},
    ///             {"x":0,"y":0,"depot":0,"skills":[0,0,1]}],
    ///   "tasks":[{"x":0,"y":1,"requires":[1,1,1],"duration":1}]}"#)?;
    /// assert_eq!(inst.fewest_robots(0), 3);
    /// # Ok::<(), afg_schedule::ScheduleError>(())
    /// ```
    pub fn fewest_robots(&self, task: usize) -> usize {
        let mut fewest = self.tasks[task].team_floor();
        let needs: Vec<u32> = (0..self.num_skills())
            .map(|s| self.task_requires(task, s))
            .collect();
        for (s, &need) in needs.iter().enumerate() {
            let most = (0..self.num_robots())
                .map(|i| self.robot_skill(i, s))
                .max()
                .unwrap_or(0);
            if need > 0 && most > 0 {
                fewest = fewest.max(need.div_ceil(most) as usize);
            }
        }
        let useful = |i: usize| -> u32 {
            needs
                .iter()
                .enumerate()
                .map(|(s, &need)| self.robot_skill(i, s).min(need))
                .sum()
        };
        let most_useful = (0..self.num_robots()).map(useful).max().unwrap_or(0);
        if most_useful > 0 {
            fewest = fewest.max(needs.iter().sum::<u32>().div_ceil(most_useful) as usize);
        }
        fewest
    }

    /// A certified lower bound on the makespan of every schedule of this instance.
    ///
    /// # Examples
    /// ```
    /// use afg_schedule::ScheduleInstance;
    /// let inst = ScheduleInstance::from_json(r#"{"speed":1,"max_wait":10,"depots":[[0,0]],
    ///   "robots":[{"x":0,"y":0,"depot":0},{"x":0,"y":0,"depot":0}],
    ///   "tasks":[{"x":3,"y":4,"min_team":2,"duration":1}]}"#)?;
    /// let bound = inst.lower_bound();
    /// assert_eq!(bound.makespan, 11.0); // both must go out, work and come back
    /// # Ok::<(), afg_schedule::ScheduleError>(())
    /// ```
    pub fn lower_bound(&self) -> Bound {
        let (n, m) = (self.num_robots(), self.num_tasks());
        let team: Vec<usize> = (0..m).map(|j| self.fewest_robots(j)).collect();
        let all: Vec<usize> = (0..n).collect();
        let (work, driving) = self.crew_load(&team, &all);
        let skill_loads = (0..self.num_skills())
            .map(|s| {
                let crew: Vec<usize> = (0..n).filter(|&i| self.robot_skill(i, s) > 0).collect();
                let most = crew
                    .iter()
                    .map(|&i| self.robot_skill(i, s))
                    .max()
                    .unwrap_or(0);
                if most == 0 {
                    return 0.0;
                }
                let need: Vec<usize> = (0..m)
                    .map(|j| self.task_requires(j, s).div_ceil(most) as usize)
                    .collect();
                let (work, driving) = self.crew_load(&need, &crew);
                (work + driving) / crew.len() as f64
            })
            .collect::<Vec<f64>>();
        let trip = (0..m)
            .map(|j| {
                let out = (0..n).map(|i| self.travel_time(Place::Start(i), Place::Task(j)));
                let back = (0..n).map(|i| {
                    if self.return_to_depot {
                        self.travel_time(Place::Task(j), self.depot_place(i))
                    } else {
                        0.0
                    }
                });
                out.fold(f64::INFINITY, f64::min)
                    + self.tasks[j].duration
                    + back.fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max);
        let load = (work + driving) / n as f64;
        Bound {
            makespan: skill_loads.iter().copied().fold(load.max(trip), f64::max),
            load,
            skill_loads,
            trip,
            driving,
            work,
        }
    }

    /// The transportation problem's optimum (see the module's text); above
    /// [`TRANSPORT_LIMIT`] tasks, the cheaper and weaker sum of each visit's shortest leg in.
    fn least_driving(&self, team: &[usize], crew: &[usize]) -> f64 {
        if self.num_tasks() > TRANSPORT_LIMIT {
            return self.shortest_legs(team, crew);
        }
        let m = self.num_tasks();
        // Robots that start at one place and go home to one depot form one source and one sink.
        let mut starts: Vec<([f64; 2], usize)> = Vec::new();
        for r in crew.iter().map(|&i| &self.robots[i]) {
            match starts.iter_mut().find(|(p, _)| *p == [r.x, r.y]) {
                Some(s) => s.1 += 1,
                None => starts.push(([r.x, r.y], 1)),
            }
        }
        let mut homes = vec![0usize; self.depots.len()];
        for &i in crew {
            homes[self.robots[i].depot] += 1;
        }
        let point = |j: usize| [self.tasks[j].x, self.tasks[j].y];
        let time = |a: [f64; 2], b: [f64; 2]| crate::instance::straight(a, b) / self.speed;
        let needed = || (0..m).filter(|&j| team[j] > 0);
        let left: Vec<([f64; 2], usize, Option<usize>)> = needed()
            .map(|j| (point(j), team[j], Some(j)))
            .chain(starts.iter().map(|&(p, c)| (p, c, None)))
            .collect();
        let right: Vec<([f64; 2], usize, Option<usize>, bool)> = needed()
            .map(|j| (point(j), team[j], Some(j), false))
            .chain(
                homes
                    .iter()
                    .enumerate()
                    .filter(|(_, c)| **c > 0)
                    .map(|(d, &c)| (self.depots[d], c, None, true)),
            )
            .collect();
        let cost: Vec<Vec<f64>> = left
            .iter()
            .map(|&(a, _, lj)| {
                right
                    .iter()
                    .map(|&(b, _, rj, home)| match (lj, rj) {
                        (Some(x), Some(y)) if x == y => f64::INFINITY,
                        _ if home && !self.return_to_depot => 0.0,
                        _ => time(a, b),
                    })
                    .collect()
            })
            .collect();
        let supply: Vec<usize> = left.iter().map(|l| l.1).collect();
        let demand: Vec<usize> = right.iter().map(|r| r.1).collect();
        let units: usize = supply.iter().sum();
        debug_assert_eq!(units, demand.iter().sum::<usize>());
        let shared = needed().count();
        let task = |a: usize| left[a].2.expect("the first nodes are tasks");
        let nodes = left.len() + right.len();
        let rounds = (ONE_WAY_WORK / (units * nodes * nodes).max(1)).min(ONE_WAY_ROUNDS);
        crate::transport::min_cost_one_way(
            &supply,
            &demand,
            &cost,
            shared,
            |a, b| {
                cost[a][b] > 0.0
                    || self.tasks[task(a)].duration + self.tasks[task(b)].duration > 0.0
            },
            rounds,
        )
    }
}

impl ScheduleInstance {
    /// The work `team[j]` robots of `crew` must do at every task, and their least driving.
    fn crew_load(&self, team: &[usize], crew: &[usize]) -> (f64, f64) {
        let work = team
            .iter()
            .zip(&self.tasks)
            .map(|(&k, t)| k as f64 * t.duration)
            .sum();
        (work, self.least_driving(team, crew))
    }

    /// Each visit's shortest leg in (from a start or another task) and each robot's
    /// shortest way home from a task or its start: a weaker bound on all driving.
    fn shortest_legs(&self, team: &[usize], crew: &[usize]) -> f64 {
        let m = self.num_tasks();
        let into = (0..m).filter(|&j| team[j] > 0).map(|j| {
            let from_tasks = (0..m)
                .filter(|&a| a != j && team[a] > 0)
                .map(|a| self.travel_time(Place::Task(a), Place::Task(j)));
            let from_starts = crew
                .iter()
                .map(|&i| self.travel_time(Place::Start(i), Place::Task(j)));
            team[j] as f64 * from_tasks.chain(from_starts).fold(f64::INFINITY, f64::min)
        });
        let home = crew.iter().map(|&i| {
            if !self.return_to_depot {
                return 0.0;
            }
            let d = self.depot_place(i);
            (0..m)
                .filter(|&j| team[j] > 0)
                .map(|j| self.travel_time(Place::Task(j), d))
                .chain(std::iter::once(self.travel_time(Place::Start(i), d)))
                .fold(f64::INFINITY, f64::min)
        });
        into.sum::<f64>() + home.sum::<f64>()
    }
}

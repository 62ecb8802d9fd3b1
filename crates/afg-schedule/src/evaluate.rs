//! The exact evaluator: a schedule played under the rules of DCMRTA's simulator.
//!
//! Robots leave their start at time 0. A robot joins a task's team when it *leaves* for
//! it (commitment order: departure time, ties by robot index). Once the committed team
//! has `min_team` robots and holds every skill the task `requires`, the task starts at
//! the latest arrival among them and ends `duration` later; they all leave at its end.
//! A robot that sets off for a task already staffed is an extra: under [`Rules::Dcmrta`]
//! it goes there and is released at the finish (even if it arrives later, which a good
//! schedule never relies on), under [`Rules::Heteromrta`] it skips the task. After its
//! last task a robot drives back to its depot; the makespan is the last return.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use serde::{Deserialize, Serialize};

use crate::{Place, Rules, ScheduleError, ScheduleInstance};

/// One ordered list of task ids per robot.
///
/// # Examples
/// ```
/// use afg_schedule::{Schedule, ScheduleInstance};
/// let inst = ScheduleInstance::from_json(r#"{"speed":1,"max_wait":10,"depots":[[0,0]],
///   "robots":[{"x":0,"y":0,"depot":0},{"x":0,"y":0,"depot":0}],
///   "tasks":[{"x":3,"y":4,"min_team":2,"duration":1}]}"#)?;
/// let run = inst.evaluate(&Schedule { routes: vec![vec![0], vec![0]] })?;
/// assert_eq!(run.makespan, 11.0); // 5 there, 1 at work, 5 back
/// assert_eq!(run.travel, 20.0);
/// # Ok::<(), afg_schedule::ScheduleError>(())
/// ```
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Schedule {
    /// `routes[i]`: the tasks robot i performs, in order.
    pub routes: Vec<Vec<usize>>,
}

/// A schedule as a line of a file: the routes and, optionally, what instance and method.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScheduleRecord {
    /// The instance's `index` in its set.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub index: Option<usize>,
    /// The method that made it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub method: Option<String>,
    /// One ordered list of task ids per robot.
    pub routes: Vec<Vec<usize>>,
}

impl ScheduleRecord {
    /// Parses one record from JSON.
    pub fn from_json(text: &str) -> Result<Self, ScheduleError> {
        serde_json::from_str(text).map_err(|e| ScheduleError::Parse {
            line: e.line(),
            message: e.to_string(),
        })
    }

    /// The routes as a [`Schedule`].
    pub fn schedule(&self) -> Schedule {
        Schedule {
            routes: self.routes.clone(),
        }
    }
}

/// Reads a JSON Lines file of schedule records.
pub fn read_schedules(path: &std::path::Path) -> Result<Vec<ScheduleRecord>, ScheduleError> {
    let text = std::fs::read_to_string(path).map_err(|source| ScheduleError::Io {
        path: path.display().to_string(),
        source,
    })?;
    crate::instance::parse_lines(&text, ScheduleRecord::from_json)
}

/// What a robot was at a task it set off for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Role {
    /// One of the team the task started with.
    Team,
    /// Committed after the team was complete (DCMRTA's rules): there, but not needed.
    Extra,
    /// Skipped because the team was complete (HeteroMRTA's rules): never went.
    Skipped,
}

/// One robot at one task.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Visit {
    /// The task.
    pub task: usize,
    /// What the robot was there.
    pub role: Role,
    /// When it left for it.
    pub depart: f64,
    /// When it arrived (equal to `depart` when skipped).
    pub arrive: f64,
    /// When it left again (the task's finish; `depart` when skipped).
    pub leave: f64,
}

/// A robot kept waiting at an incomplete team longer than the rule allows.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LongWait {
    /// The robot.
    pub robot: usize,
    /// The task.
    pub task: usize,
    /// How long it waited for its team.
    pub wait: f64,
}

/// A schedule played out: its makespan, its timeline and anything that breaks the rules.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Evaluation {
    /// When the last robot is back at its depot (or, without returns, the last finish).
    pub makespan: f64,
    /// Total distance driven by all robots.
    pub travel: f64,
    /// Mean over robots of each one's total wait at its tasks, from its arrival to the latest
    /// arrival among the robots that set off for the task (DCMRTA's `waiting_time`).
    pub waiting: f64,
    /// The longest any team member waited for its team to complete.
    pub longest_wait: f64,
    /// The rule the waits were checked against.
    pub max_wait: f64,
    /// When each task started.
    pub start: Vec<f64>,
    /// When each task finished.
    pub finish: Vec<f64>,
    /// When each robot was back (its last finish where robots do not return).
    pub back: Vec<f64>,
    /// Each robot's visits, in order.
    pub visits: Vec<Vec<Visit>>,
    /// Team members that waited longer than `max_wait`: in the simulator they give up.
    pub long_waits: Vec<LongWait>,
    /// Extras released at a finish before they arrived (DCMRTA's simulator allows it).
    pub released_before_arrival: Vec<(usize, usize)>,
}

/// Where the robots' time goes up to the makespan, as means over the robots: the four
/// add up to the makespan.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TimeUse {
    /// At tasks, as a member of their teams, from start to finish.
    pub working: f64,
    /// On the way: to each task set off for, and home.
    pub driving: f64,
    /// At tasks, not working: a member waiting for the rest of its team, an extra
    /// waiting to be released.
    pub waiting: f64,
    /// The rest: back home before the makespan. (Where an extra is released before it
    /// arrives, which no valid schedule does, its legs overlap and this can fall below 0.)
    pub idle: f64,
}

impl Evaluation {
    /// True when nobody waits beyond `max_wait` and no extra relies on an early release.
    pub fn is_valid(&self) -> bool {
        self.long_waits.is_empty() && self.released_before_arrival.is_empty()
    }

    /// Where the robots' time goes ([`TimeUse`]).
    ///
    /// # Examples
    /// ```
    /// use afg_schedule::{Schedule, ScheduleInstance};
    /// let inst = ScheduleInstance::from_json(r#"{"speed":1,"max_wait":10,"depots":[[0,0]],
    ///   "robots":[{"x":0,"y":0,"depot":0},{"x":0,"y":0,"depot":0}],
    ///   "tasks":[{"x":0,"y":2,"min_team":2,"duration":1},{"x":0,"y":4,"min_team":1,"duration":3}]}"#)?;
    /// let use_ = inst.evaluate(&Schedule { routes: vec![vec![0, 1], vec![0]] })?.time_use();
    /// // Robot 0: 8 driving, 4 working, back at 12; robot 1: 4 driving, 1 working, back at 5.
    /// assert_eq!((use_.working, use_.driving, use_.waiting, use_.idle), (2.5, 6.0, 0.0, 3.5));
    /// # Ok::<(), afg_schedule::ScheduleError>(())
    /// ```
    pub fn time_use(&self) -> TimeUse {
        let mut sum = TimeUse::default();
        for (visits, &back) in self.visits.iter().zip(&self.back) {
            let mut free = 0.0;
            let mut robot = TimeUse::default();
            for v in visits.iter().filter(|v| v.role != Role::Skipped) {
                robot.driving += v.arrive - v.depart;
                if v.role == Role::Team {
                    robot.working += self.finish[v.task] - self.start[v.task];
                    robot.waiting += self.start[v.task] - v.arrive;
                } else {
                    robot.waiting += (v.leave - v.arrive).max(0.0);
                }
                free = v.leave;
            }
            robot.driving += back - free;
            robot.idle = self.makespan - robot.working - robot.driving - robot.waiting;
            sum.working += robot.working;
            sum.driving += robot.driving;
            sum.waiting += robot.waiting;
            sum.idle += robot.idle;
        }
        let n = self.back.len().max(1) as f64;
        TimeUse {
            working: sum.working / n,
            driving: sum.driving / n,
            waiting: sum.waiting / n,
            idle: sum.idle / n,
        }
    }
}

/// A time that sorts totally (the evaluator never produces NaN).
#[derive(Clone, Copy, PartialEq)]
struct Time(f64);
impl Eq for Time {}
impl PartialOrd for Time {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Time {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

/// The team committed to one task so far.
#[derive(Clone, Default)]
struct Forming {
    members: Vec<usize>,
    held: Vec<u64>,
    latest_arrival: f64,
    complete: bool,
}

impl ScheduleInstance {
    /// Plays `schedule` under the instance's rules and its `max_wait`.
    pub fn evaluate(&self, schedule: &Schedule) -> Result<Evaluation, ScheduleError> {
        self.evaluate_with(schedule, self.max_wait)
    }

    /// Plays `schedule`, reporting every team member that waits longer than `max_wait`.
    ///
    /// A schedule that names an unknown task, leaves one out, visits a task twice or has
    /// the wrong number of routes is an error, and so is one whose robots wait for each
    /// other in a cycle ([`ScheduleError::Deadlock`], naming who waits where).
    pub fn evaluate_with(
        &self,
        schedule: &Schedule,
        max_wait: f64,
    ) -> Result<Evaluation, ScheduleError> {
        self.check_schedule(schedule)?;
        if max_wait.is_nan() || max_wait <= 0.0 {
            return Err(ScheduleError::Setting(format!(
                "max_wait must be above 0, not {max_wait}"
            )));
        }
        Play::new(self, schedule).run(max_wait)
    }

    /// Checks that `schedule` has one route per robot, names only this instance's tasks,
    /// visits no task twice in one route and leaves no task out.
    pub fn check_schedule(&self, schedule: &Schedule) -> Result<(), ScheduleError> {
        if schedule.routes.len() != self.num_robots() {
            return Err(ScheduleError::BadSchedule(format!(
                "has {} routes for {} robots",
                schedule.routes.len(),
                self.num_robots()
            )));
        }
        let mut seen = vec![false; self.num_tasks()];
        for (i, route) in schedule.routes.iter().enumerate() {
            let mut mine = std::collections::HashSet::new();
            for &j in route {
                if j >= self.num_tasks() {
                    return Err(ScheduleError::BadSchedule(format!(
                        "sends robot {i} to task {j}, but the tasks are 0 to {}",
                        self.num_tasks() - 1
                    )));
                }
                if !mine.insert(j) {
                    return Err(ScheduleError::BadSchedule(format!(
                        "sends robot {i} to task {j} twice"
                    )));
                }
                seen[j] = true;
            }
        }
        if let Some(j) = seen.iter().position(|&s| !s) {
            let missing = seen.iter().filter(|&&s| !s).count();
            return Err(ScheduleError::BadSchedule(format!(
                "leaves out task {j}{}: every task needs a team",
                if missing > 1 {
                    format!(" and {} more", missing - 1)
                } else {
                    String::new()
                }
            )));
        }
        Ok(())
    }
}

/// The state of one play of a schedule.
struct Play<'a> {
    inst: &'a ScheduleInstance,
    routes: &'a [Vec<usize>],
    next: Vec<usize>,
    at: Vec<Place>,
    forming: Vec<Forming>,
    start: Vec<f64>,
    finish: Vec<f64>,
    visits: Vec<Vec<Visit>>,
    back: Vec<f64>,
    travel: f64,
    queue: BinaryHeap<Reverse<(Time, usize)>>,
}

impl<'a> Play<'a> {
    fn new(inst: &'a ScheduleInstance, schedule: &'a Schedule) -> Self {
        let (n, m) = (inst.num_robots(), inst.num_tasks());
        let empty = Forming {
            held: vec![0; inst.num_skills()],
            ..Forming::default()
        };
        Play {
            inst,
            routes: &schedule.routes,
            next: vec![0; n],
            at: (0..n).map(Place::Start).collect(),
            forming: vec![empty; m],
            start: vec![f64::NAN; m],
            finish: vec![f64::NAN; m],
            visits: vec![Vec::new(); n],
            back: vec![0.0; n],
            travel: 0.0,
            queue: (0..n).map(|i| Reverse((Time(0.0), i))).collect(),
        }
    }

    fn run(mut self, max_wait: f64) -> Result<Evaluation, ScheduleError> {
        while let Some(Reverse((Time(t), i))) = self.queue.pop() {
            match self.routes[i].get(self.next[i]).copied() {
                Some(j) => {
                    self.next[i] += 1;
                    self.depart(i, j, t);
                }
                None => self.go_home(i, t),
            }
        }
        let waiting: Vec<(usize, usize)> = (0..self.inst.num_tasks())
            .filter(|&j| !self.forming[j].complete)
            .flat_map(|j| self.forming[j].members.iter().map(move |&i| (i, j)))
            .collect();
        if !waiting.is_empty() {
            let mut waiting = waiting;
            waiting.sort_unstable();
            return Err(ScheduleError::Deadlock { waiting });
        }
        Ok(self.finish_up(max_wait))
    }

    fn depart(&mut self, i: usize, j: usize, t: f64) {
        let complete = self.forming[j].complete;
        if complete && self.inst.rules == Rules::Heteromrta {
            self.visits[i].push(Visit {
                task: j,
                role: Role::Skipped,
                depart: t,
                arrive: t,
                leave: t,
            });
            self.queue.push(Reverse((Time(t), i)));
            return;
        }
        let d = self.inst.distance(self.at[i], Place::Task(j));
        self.travel += d;
        self.at[i] = Place::Task(j);
        let arrive = t + d / self.inst.speed;
        if complete {
            let leave = self.finish[j];
            self.visits[i].push(Visit {
                task: j,
                role: Role::Extra,
                depart: t,
                arrive,
                leave,
            });
            self.queue.push(Reverse((Time(leave), i)));
            return;
        }
        self.visits[i].push(Visit {
            task: j,
            role: Role::Team,
            depart: t,
            arrive,
            leave: f64::NAN,
        });
        let f = &mut self.forming[j];
        f.members.push(i);
        f.latest_arrival = f.latest_arrival.max(arrive);
        for (s, h) in f.held.iter_mut().enumerate() {
            *h += u64::from(self.inst.robot_skill(i, s));
        }
        let task = &self.inst.tasks[j];
        let enough = f.members.len() >= task.team_floor()
            && f.held
                .iter()
                .enumerate()
                .all(|(s, &h)| h >= u64::from(self.inst.task_requires(j, s)));
        if enough {
            f.complete = true;
            self.start[j] = f.latest_arrival;
            self.finish[j] = f.latest_arrival + task.duration;
            for &m in &f.members {
                let visit = self.visits[m].last_mut().expect("a member has visited");
                visit.leave = self.finish[j];
                self.queue.push(Reverse((Time(self.finish[j]), m)));
            }
        }
    }

    fn go_home(&mut self, i: usize, t: f64) {
        if !self.inst.return_to_depot {
            self.back[i] = t;
            return;
        }
        let d = self.inst.distance(self.at[i], self.inst.depot_place(i));
        self.travel += d;
        self.back[i] = t + d / self.inst.speed;
    }

    fn finish_up(self, max_wait: f64) -> Evaluation {
        let n = self.inst.num_robots();
        let mut latest = vec![f64::NEG_INFINITY; self.inst.num_tasks()];
        for v in self
            .visits
            .iter()
            .flatten()
            .filter(|v| v.role != Role::Skipped)
        {
            latest[v.task] = latest[v.task].max(v.arrive);
        }
        let mut waited = vec![0.0; n];
        let (mut long_waits, mut released_before_arrival, mut longest_wait) =
            (Vec::new(), Vec::new(), 0.0f64);
        for (i, visits) in self.visits.iter().enumerate() {
            for v in visits {
                match v.role {
                    Role::Skipped => {}
                    Role::Extra => {
                        waited[i] += latest[v.task] - v.arrive;
                        if v.leave < v.arrive {
                            released_before_arrival.push((i, v.task));
                        }
                    }
                    Role::Team => {
                        waited[i] += latest[v.task] - v.arrive;
                        let wait = self.start[v.task] - v.arrive;
                        longest_wait = longest_wait.max(wait);
                        if wait > max_wait {
                            long_waits.push(LongWait {
                                robot: i,
                                task: v.task,
                                wait,
                            });
                        }
                    }
                }
            }
        }
        Evaluation {
            makespan: self.back.iter().copied().fold(0.0, f64::max),
            travel: self.travel,
            waiting: waited.iter().sum::<f64>() / n as f64,
            longest_wait,
            max_wait,
            start: self.start,
            finish: self.finish,
            back: self.back,
            visits: self.visits,
            long_waits,
            released_before_arrival,
        }
    }
}

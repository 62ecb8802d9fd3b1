//! The event-driven simulator: exact arrival and completion times, a decision at every
//! event, any allocator in the loop.

use std::borrow::Cow;
use std::cmp::Ordering;
use std::collections::{BinaryHeap, HashMap};

use afg_baseline::Allocator;
use afg_game::{Instance, Point, Preference, Task};
use serde::{Deserialize, Serialize};

use crate::{Mission, MissionError};

/// How each decision is made.
#[derive(Clone, Copy)]
pub enum Replan<'a> {
    /// The allocator, from scratch, at every decision.
    Scratch(&'a dyn Allocator),
    /// The allocator at the first decision; after it, survivors keep their task (if it
    /// is still open) and best-response dynamics under `preference` settle the rest.
    Warm {
        /// The first decision's allocator.
        first: &'a dyn Allocator,
        /// The dynamics' preference.
        preference: Preference,
    },
    /// The exact optimum, re-solved at every decision from the previous decision's task
    /// prices (a new task starts at [`Optimum::start_price`](afg_baseline::Optimum::start_price)):
    /// the same optimum, found from a warm start.
    WarmOpt,
    /// No central decision: the robots run a decentralised method round by round and
    /// each heads where its own view says.
    Decentralised(&'a Decentralised),
}

/// How long a decision takes in mission time: robots act on it only once it is made.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case", tag = "kind")]
pub enum Latency {
    /// Decisions take no mission time.
    None,
    /// Each decision takes this many time units.
    Fixed {
        /// Time units per decision.
        delay: f64,
    },
    /// Each decision takes the allocator's measured compute time times `factor`
    /// (mission time units per second of compute): not reproducible run to run.
    Measured {
        /// Mission time units per second.
        factor: f64,
    },
}

/// The options of a run besides the allocator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunOptions {
    /// Also decide every this many time units, not only at events.
    pub replan_every: Option<f64>,
    /// How long decisions take.
    pub latency: Latency,
    /// Keep every event and decision ([`MissionRun::trace`]).
    pub trace: bool,
    /// Snapshot the whole state every this many time units ([`MissionRun::frames`]:
    /// the animation's frames).
    pub frame_every: Option<f64>,
    /// Commitment: robots at work stay until their task is done.
    pub commit: bool,
    /// Hysteresis: a travelling robot switches task only for a gain (in balanced
    /// score, the decision's game) above this.
    pub hysteresis: Option<f64>,
}

impl Default for RunOptions {
    fn default() -> Self {
        RunOptions {
            frame_every: None,
            commit: false,
            hysteresis: None,
            replan_every: None,
            latency: Latency::None,
            trace: false,
        }
    }
}

/// One event of a run, for `--trace` (JSON Lines).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "event")]
pub enum TraceEvent {
    /// A task appeared.
    TaskAppears {
        /// Mission time.
        time: f64,
        /// The task.
        task: usize,
    },
    /// A task's workload was done.
    TaskDone {
        /// Mission time.
        time: f64,
        /// The task.
        task: usize,
    },
    /// A robot failed.
    RobotFails {
        /// Mission time.
        time: f64,
        /// The robot.
        robot: usize,
    },
    /// A robot came back.
    RobotReturns {
        /// Mission time.
        time: f64,
        /// The robot.
        robot: usize,
    },
    /// A robot reached its task.
    Arrival {
        /// Mission time.
        time: f64,
        /// The robot.
        robot: usize,
        /// Its task.
        task: usize,
    },
    /// A decision took effect.
    Decision {
        /// When it took effect.
        time: f64,
        /// When it was asked for.
        asked: f64,
        /// Every robot's task from then on (−1: none).
        tasks: Vec<i64>,
        /// Every robot's position then.
        positions: Vec<[f64; 2]>,
        /// The allocator's compute time (seconds).
        compute_s: f64,
    },
}

/// Where the mission stood after an event.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TimelinePoint {
    /// Mission time.
    pub time: f64,
    /// Tasks appeared and not yet done.
    pub open: usize,
    /// Tasks done.
    pub done: usize,
    /// Reward of the tasks done (`Σ r_j W_j`).
    pub reward: f64,
}

/// The metrics of a run (docs/missions.md defines each).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Metrics {
    /// Tasks whose workload was done by the horizon.
    pub tasks_done: usize,
    /// Tasks in the mission.
    pub tasks: usize,
    /// `Σ r_j W_j` over the tasks done: the score to rank methods by.
    pub reward_done: f64,
    /// `Σ r_j W_j` over all tasks: the most a run can score.
    pub reward_total: f64,
    /// Mean time from a task's appearance to its completion, over the tasks done.
    pub latency_mean: Option<f64>,
    /// Its 95th percentile (nearest rank).
    pub latency_p95: Option<f64>,
    /// Its maximum.
    pub latency_max: Option<f64>,
    /// When the last task was done, if every task was.
    pub makespan: Option<f64>,
    /// When the run stopped: the makespan, or the horizon.
    pub end: f64,
    /// Distance travelled by all robots.
    pub distance: f64,
    /// Robots switching from one task to another.
    pub reassignments: u64,
    /// Decisions taken.
    pub decisions: u64,
    /// Robot–task pairs of the decisions' games (Σ robots × open tasks): what any exact
    /// method must read at least once.
    pub pairs: u64,
    /// The allocator's compute time per decision, mean (seconds).
    pub compute_mean_s: f64,
    /// Its maximum.
    pub compute_max_s: f64,
    /// In total.
    pub compute_total_s: f64,
    /// Work done on every task (done or not) by the end.
    pub work_done: f64,
    /// `Σ r_j` times the work done on each task (done or not): the reward done plus
    /// the value of the work on tasks left unfinished.
    pub work_value: f64,
    /// A decentralised method's rounds, traffic and response times (for it, each
    /// round counts as a decision).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub swarm: Option<SwarmMetrics>,
}

/// A finished run: its metrics, its timeline, and (if asked) every event.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MissionRun {
    /// The metrics.
    pub metrics: Metrics,
    /// Open and done tasks and reward after every event.
    pub timeline: Vec<TimelinePoint>,
    /// Every event and decision, if [`RunOptions::trace`].
    pub trace: Vec<TraceEvent>,
    /// Snapshots every [`RunOptions::frame_every`] time units.
    pub frames: Vec<Frame>,
}

/// The whole state at one moment (for animations).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Frame {
    /// Mission time.
    pub time: f64,
    /// Every robot's position.
    pub positions: Vec<[f32; 2]>,
    /// Every robot's task (−1: none; −2: failed).
    pub tasks: Vec<i32>,
    /// Every task's work left as a share of its workload (−1: not yet appeared; 0: done).
    pub left: Vec<f32>,
}

impl MissionRun {
    /// The trace as JSON Lines, one event a line (`afg mission run --trace`).
    ///
    /// # Examples
    /// ```
    /// use afg_baseline::Greedy;
    /// use afg_mission::{MissionConfig, Preset, Replan, RunOptions, simulate};
    /// let mission = MissionConfig::new(Preset::Static, 5, 2, 1).generate()?;
    /// let options = RunOptions { trace: true, ..RunOptions::default() };
    /// let run = simulate(&mission, Replan::Scratch(&Greedy), options)?;
    /// assert_eq!(run.trace_jsonl().lines().count(), run.trace.len());
    /// # Ok::<(), afg_mission::MissionError>(())
    /// ```
    pub fn trace_jsonl(&self) -> String {
        self.trace
            .iter()
            .map(|e| serde_json::to_string(e).expect("an event serialises") + "\n")
            .collect()
    }
}

/// The work rate of `n` robots at a task of base `eps`: `log_eps(n + eps − 1)` (one
/// robot: 1), so the coalition value `F_j(n)` is the task's reward rate.
///
/// # Examples
/// ```
/// assert_eq!(afg_mission::work_rate(1, 3.0), 1.0);
/// assert!((afg_mission::work_rate(2, 2.0) - 3f64.log2()).abs() < 1e-12);
/// assert_eq!(afg_mission::work_rate(0, 2.0), 0.0);
/// ```
pub fn work_rate(n: usize, eps: f64) -> f64 {
    if n == 0 {
        0.0
    } else {
        (n as f64 + eps - 1.0).ln() / eps.ln()
    }
}

/// The paper's game of `robots` (where they are) and `tasks` of `mission`: GRAPE's game
/// where the mission allows idling, or where the tasks cannot hold every robot (the
/// extra robots then idle).
fn mission_game(
    mission: &Mission,
    robots: Vec<Point>,
    tasks: Vec<Task>,
) -> Result<Instance, MissionError> {
    let room = (tasks.iter())
        .map(|t| t.capacity.unwrap_or(usize::MAX))
        .fold(0usize, usize::saturating_add);
    Ok(if mission.allow_void || room < robots.len() {
        Instance::with_void(robots, tasks, mission.beta)?
    } else {
        Instance::new(robots, tasks, mission.beta)?
    })
}

/// A robot's state.
#[derive(Clone, Copy, Debug)]
struct Robot {
    alive: bool,
    /// Where it was when its leg began (its position if idle or at its task).
    from: Point,
    /// When the leg began.
    since: f64,
    /// Its task, if any.
    task: Option<usize>,
    /// Whether it has reached its task.
    there: bool,
}

/// A task's state.
#[derive(Clone, Copy, Debug, Default)]
struct TaskState {
    open: bool,
    remaining: f64,
    done_at: Option<f64>,
    /// Living robots at the task.
    present: usize,
}

/// A decision computed but not yet in effect.
struct Pending {
    ready: f64,
    asked: f64,
    /// Robot index → task (mission indices).
    tasks: Vec<(usize, Option<usize>)>,
    compute_s: f64,
}

/// A robot's arrival at the end of its current leg, earliest first in a heap.
#[derive(Clone, Copy, Debug)]
struct Due {
    time: f64,
    robot: u32,
    leg: u64,
}

impl PartialEq for Due {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Due {}
impl PartialOrd for Due {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Due {
    /// Reversed, so that `BinaryHeap` pops the earliest; ties by robot index.
    fn cmp(&self, other: &Self) -> Ordering {
        other
            .time
            .total_cmp(&self.time)
            .then(other.robot.cmp(&self.robot))
            .then(other.leg.cmp(&self.leg))
    }
}

/// Relative tolerance under which an arrival or completion counts as reached.
const REACHED: f64 = 1e-9;

/// Runs `mission` with decisions by `replan` (see docs/missions.md for the model).
///
/// # Errors
/// [`MissionError::Alloc`] if the allocator fails, [`MissionError::Invalid`] for an
/// option out of range.
///
/// # Examples
/// ```
/// use afg_baseline::Greedy;
/// use afg_mission::{MissionConfig, Preset, Replan, RunOptions, simulate};
/// let mission = MissionConfig::new(Preset::Static, 20, 4, 1).generate()?;
/// let run = simulate(&mission, Replan::Scratch(&Greedy), RunOptions::default())?;
/// assert_eq!(run.metrics.tasks_done, 4);
/// assert!(run.metrics.makespan.is_some());
/// # Ok::<(), afg_mission::MissionError>(())
/// ```
pub fn simulate(
    mission: &Mission,
    replan: Replan<'_>,
    options: RunOptions,
) -> Result<MissionRun, MissionError> {
    simulate_with(mission, replan, options, |_| {})
}

/// [`simulate`], telling `on_time` the mission time after every event (a progress
/// bar).
///
/// # Errors
/// As [`simulate`].
///
/// # Examples
/// ```
/// use afg_baseline::Greedy;
/// use afg_mission::{MissionConfig, Preset, Replan, RunOptions, simulate_with};
/// let mission = MissionConfig::new(Preset::Waves, 10, 4, 1).generate()?;
/// let mut last = 0.0;
/// simulate_with(&mission, Replan::Scratch(&Greedy), RunOptions::default(), |t| last = t)?;
/// assert!(last > 0.0 && last <= mission.horizon);
/// # Ok::<(), afg_mission::MissionError>(())
/// ```
pub fn simulate_with(
    mission: &Mission,
    replan: Replan<'_>,
    options: RunOptions,
    on_time: impl FnMut(f64),
) -> Result<MissionRun, MissionError> {
    check_options(&options)?;
    let mut sim = Sim::new(Cow::Borrowed(mission), Some(replan), options);
    if let Replan::Decentralised(config) = replan {
        let central = options.replan_every.is_some()
            || options.latency != Latency::None
            || options.commit
            || options.hysteresis.is_some();
        if central {
            return Err(MissionError::Invalid(
                "replanning, latency, commitment and hysteresis are for central decisions; a decentralised method runs at its rounds per time unit".into(),
            ));
        }
        sim.swarm = Some(SwarmState::new(mission, config)?);
    }
    sim.run(on_time)?;
    Ok(sim.finish())
}

pub(crate) fn check_options(options: &RunOptions) -> Result<(), MissionError> {
    let positive = |x: f64| x.is_finite() && x > 0.0;
    if options.replan_every.is_some_and(|r| !positive(r)) {
        return Err(MissionError::Invalid(
            "the replanning interval must be finite and positive".into(),
        ));
    }
    if options.hysteresis.is_some_and(|h| h.is_nan() || h < 0.0) {
        return Err(MissionError::Invalid(
            "the hysteresis threshold must be ≥ 0".into(),
        ));
    }
    if options.frame_every.is_some_and(|r| !positive(r)) {
        return Err(MissionError::Invalid(
            "the time between frames must be finite and positive".into(),
        ));
    }
    let latency_ok = match options.latency {
        Latency::None => true,
        Latency::Fixed { delay } => delay.is_finite() && delay >= 0.0,
        Latency::Measured { factor } => factor.is_finite() && factor >= 0.0,
    };
    if !latency_ok {
        return Err(MissionError::Invalid(
            "the decision latency must be finite and ≥ 0".into(),
        ));
    }
    Ok(())
}

/// The simulator's state.
struct Sim<'m, 'a> {
    mission: Cow<'m, Mission>,
    /// How decisions are made (`None`: from outside, by [`MissionEnv`]'s agents).
    replan: Option<Replan<'a>>,
    options: RunOptions,
    now: f64,
    robots: Vec<Robot>,
    tasks: Vec<TaskState>,
    /// Time-ordered scheduled events: (time, kind order, what).
    scheduled: Vec<(f64, Scheduled)>,
    next_scheduled: usize,
    next_tick: Option<f64>,
    pending: Option<Pending>,
    /// An event happened while a decision was pending: decide again when it lands.
    wanted: bool,
    /// Arrivals to come: one per leg, stale once the robot's leg count moved on.
    due: BinaryHeap<Due>,
    /// Legs begun per robot.
    legs: Vec<u64>,
    /// Whether a decision was made (warm starts start after it) and the task prices
    /// of the last (the warm optimum).
    decided: bool,
    prices: HashMap<usize, f64>,
    distance: f64,
    reassignments: u64,
    decisions: u64,
    pairs: u64,
    compute: Vec<f64>,
    timeline: Vec<TimelinePoint>,
    trace: Vec<TraceEvent>,
    frames: Vec<Frame>,
    next_frame: Option<f64>,
    /// A decentralised method's state, when one runs.
    swarm: Option<SwarmState>,
}

/// An event known in advance.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Scheduled {
    Appears(usize),
    Fails(usize),
    Returns(usize),
}

impl<'m, 'a> Sim<'m, 'a> {
    fn new(mission: Cow<'m, Mission>, replan: Option<Replan<'a>>, options: RunOptions) -> Self {
        let n = mission.robots.len();
        let robots = mission
            .robots
            .iter()
            .map(|r| Robot {
                alive: true,
                from: r.position,
                since: 0.0,
                task: None,
                there: false,
            })
            .collect();
        let tasks = mission
            .tasks
            .iter()
            .map(|t| TaskState {
                remaining: t.workload,
                ..TaskState::default()
            })
            .collect();
        let mut scheduled: Vec<(f64, Scheduled)> = mission
            .tasks
            .iter()
            .enumerate()
            .map(|(j, t)| (t.appears, Scheduled::Appears(j)))
            .collect();
        for f in &mission.failures {
            scheduled.push((f.time, Scheduled::Fails(f.robot)));
            if let Some(back) = f.returns {
                scheduled.push((back, Scheduled::Returns(f.robot)));
            }
        }
        scheduled.sort_by(|a, b| a.0.total_cmp(&b.0));
        Sim {
            mission,
            replan,
            options,
            now: 0.0,
            robots,
            tasks,
            scheduled,
            next_scheduled: 0,
            next_tick: options.replan_every,
            pending: None,
            wanted: false,
            due: BinaryHeap::new(),
            legs: vec![0; n],
            decided: false,
            prices: HashMap::new(),
            distance: 0.0,
            reassignments: 0,
            decisions: 0,
            pairs: 0,
            compute: Vec::new(),
            timeline: Vec::new(),
            trace: Vec::new(),
            frames: Vec::new(),
            next_frame: options.frame_every.map(|_| 0.0),
            swarm: None,
        }
    }

    /// Event after event until the horizon or the last task's completion.
    fn run(&mut self, mut on_time: impl FnMut(f64)) -> Result<(), MissionError> {
        loop {
            on_time(self.now);
            if self.events_now()? {
                self.decide()?;
            }
            if !self.move_on() {
                return Ok(());
            }
        }
    }

    /// What happens now: scheduled events, completions, arrivals, a swarm round, a
    /// replanning tick, a decision landing. Whether a decision is to be made now.
    fn events_now(&mut self) -> Result<bool, MissionError> {
        let mut epoch = self.scheduled_events()?;
        epoch |= self.completions();
        self.arrivals();
        if let Some(swarm) = &self.swarm {
            if swarm.next_round() <= self.now {
                self.swarm_round()?;
            }
            epoch = false;
        }
        if self.next_tick.is_some_and(|t| t <= self.now) {
            epoch = true;
            let every = self.options.replan_every.expect("ticks come from it");
            self.next_tick = Some(self.now + every);
        }
        if self.pending.as_ref().is_some_and(|p| p.ready <= self.now) {
            self.land();
            epoch |= std::mem::take(&mut self.wanted);
        }
        if epoch && self.pending.is_some() {
            self.wanted = true;
            epoch = false;
        }
        Ok(epoch)
    }

    /// After any decision now: records, then moves time to the next event. Whether the
    /// run goes on (false once every task is done or the horizon is reached).
    fn move_on(&mut self) -> bool {
        self.record();
        self.snapshot();
        if self.over() {
            return false;
        }
        let next = self.next_event().min(self.mission.horizon);
        self.advance(next);
        if self.now >= self.mission.horizon {
            self.record();
            return false;
        }
        true
    }

    /// Whether nothing more can happen: every task done.
    fn over(&self) -> bool {
        self.tasks.iter().all(|t| t.done_at.is_some())
    }

    /// The scheduled events due now; whether any is a decision epoch.
    fn scheduled_events(&mut self) -> Result<bool, MissionError> {
        let mut epoch = false;
        while let Some(&(time, what)) = self.scheduled.get(self.next_scheduled) {
            if time > self.now {
                break;
            }
            self.next_scheduled += 1;
            epoch = true;
            match what {
                Scheduled::Appears(j) => {
                    self.tasks[j].open = true;
                    self.log(TraceEvent::TaskAppears { time, task: j });
                    if let Some(swarm) = &mut self.swarm {
                        swarm.task(j, false, time);
                    }
                }
                Scheduled::Fails(i) => {
                    self.stop(i);
                    self.robots[i].alive = false;
                    self.log(TraceEvent::RobotFails { time, robot: i });
                    if let Some(swarm) = &mut self.swarm {
                        swarm.robot(i, false, time)?;
                    }
                }
                Scheduled::Returns(i) => {
                    self.robots[i].alive = true;
                    self.robots[i].since = self.now;
                    self.log(TraceEvent::RobotReturns { time, robot: i });
                    if let Some(swarm) = &mut self.swarm {
                        swarm.robot(i, true, time)?;
                    }
                }
            }
        }
        Ok(epoch)
    }

    /// Tasks whose workload is done now; their robots are free.
    fn completions(&mut self) -> bool {
        let mut any = false;
        for j in 0..self.tasks.len() {
            let t = self.tasks[j];
            let workload = self.mission.tasks[j].workload;
            if t.open && t.remaining <= REACHED * workload {
                any = true;
                self.tasks[j].open = false;
                self.tasks[j].remaining = 0.0;
                self.tasks[j].done_at = Some(self.now);
                for i in 0..self.robots.len() {
                    if self.robots[i].task == Some(j) {
                        self.stop(i);
                    }
                }
                self.log(TraceEvent::TaskDone {
                    time: self.now,
                    task: j,
                });
                if let Some(swarm) = &mut self.swarm {
                    swarm.task(j, true, self.now);
                }
            }
        }
        any
    }

    /// Robots reaching their task now (from the queue of legs, the stale ones dropped).
    fn arrivals(&mut self) {
        while let Some(&due) = self.due.peek() {
            if due.time > self.now {
                break;
            }
            self.due.pop();
            let i = due.robot as usize;
            let r = self.robots[i];
            if due.leg != self.legs[i] || !r.alive || r.there {
                continue;
            }
            if let Some(j) = r.task {
                let target = self.mission.tasks[j].position;
                self.distance += r.from.distance(target);
                self.robots[i].from = target;
                self.robots[i].since = self.now;
                self.robots[i].there = true;
                self.tasks[j].present += 1;
                self.log(TraceEvent::Arrival {
                    time: self.now,
                    robot: i,
                    task: j,
                });
            }
        }
    }

    /// When robot `i`, on its leg to task `j`, gets there.
    fn arrival_time(&self, i: usize, j: usize) -> f64 {
        let r = &self.robots[i];
        let d = r.from.distance(self.mission.tasks[j].position);
        let t = r.since + d / self.mission.robots[i].speed;
        // Within rounding of now counts as now.
        if t - self.now <= REACHED * t.abs().max(1.0) {
            self.now
        } else {
            t
        }
    }

    /// Where robot `i` is now.
    fn position(&self, i: usize) -> Point {
        let r = &self.robots[i];
        match r.task.filter(|_| r.alive && !r.there) {
            None => r.from,
            Some(j) => {
                let to = self.mission.tasks[j].position;
                let d = r.from.distance(to);
                let covered = (self.now - r.since) * self.mission.robots[i].speed;
                if d <= 0.0 || covered >= d {
                    return to;
                }
                let f = covered / d;
                Point::new(
                    r.from.x + f * (to.x - r.from.x),
                    r.from.y + f * (to.y - r.from.y),
                )
            }
        }
    }

    /// Robot `i` stops where it is: it leaves its task (and its coalition, if there).
    fn stop(&mut self, i: usize) {
        self.legs[i] += 1;
        let here = self.position(i);
        let r = self.robots[i];
        if let Some(j) = r.task {
            if r.there {
                self.tasks[j].present -= 1;
            } else if r.alive {
                self.distance += r.from.distance(here);
            }
        }
        self.robots[i] = Robot {
            from: here,
            since: self.now,
            task: None,
            there: false,
            ..r
        };
    }

    /// Robot `i` heads for task `j` from where it is.
    fn send(&mut self, i: usize, j: usize) {
        if self.robots[i].task == Some(j) {
            return;
        }
        if self.robots[i].task.is_some() {
            self.reassignments += 1;
        }
        self.stop(i);
        self.robots[i].task = Some(j);
        let time = self.arrival_time(i, j);
        self.due.push(Due {
            time,
            robot: i as u32,
            leg: self.legs[i],
        });
    }

    /// The earliest event after now: a scheduled one, an arrival, a completion, a
    /// decision landing or a replanning tick.
    fn next_event(&self) -> f64 {
        let mut next = f64::INFINITY;
        if let Some(&(t, _)) = self.scheduled.get(self.next_scheduled) {
            next = next.min(t);
        }
        if let Some(due) = self.due.peek() {
            next = next.min(due.time);
        }
        for (j, t) in self.tasks.iter().enumerate() {
            if t.open && t.present > 0 {
                let rate = work_rate(t.present, self.mission.tasks[j].eps);
                next = next.min(self.now + t.remaining / rate);
            }
        }
        if let Some(p) = &self.pending {
            next = next.min(p.ready);
        }
        let round = self.swarm.as_ref().map(SwarmState::next_round);
        for t in [self.next_tick, self.next_frame, round]
            .into_iter()
            .flatten()
        {
            next = next.min(t);
        }
        next
    }

    /// A frame, if one is due.
    fn snapshot(&mut self) {
        let (Some(due), Some(every)) = (self.next_frame, self.options.frame_every) else {
            return;
        };
        if due > self.now {
            return;
        }
        self.next_frame = Some(due + every);
        let frame = self.frame();
        self.frames.push(frame);
    }

    /// The whole state now.
    fn frame(&self) -> Frame {
        let positions = (0..self.robots.len())
            .map(|i| {
                let p = self.position(i);
                [p.x as f32, p.y as f32]
            })
            .collect();
        let tasks = self
            .robots
            .iter()
            .map(|r| match (r.alive, r.task) {
                (false, _) => -2,
                (true, None) => -1,
                (true, Some(j)) => j as i32,
            })
            .collect();
        let left = self
            .tasks
            .iter()
            .zip(&self.mission.tasks)
            .map(|(t, spec)| {
                if t.open || t.done_at.is_some() {
                    (t.remaining / spec.workload) as f32
                } else {
                    -1.0
                }
            })
            .collect();
        Frame {
            time: self.now,
            positions,
            tasks,
            left,
        }
    }

    /// Moves time to `to`: work is done at the present coalitions' rates (robots'
    /// positions follow from their legs).
    fn advance(&mut self, to: f64) {
        let dt = to - self.now;
        for (j, t) in self.tasks.iter_mut().enumerate() {
            if t.open && t.present > 0 {
                let rate = work_rate(t.present, self.mission.tasks[j].eps);
                t.remaining = (t.remaining - rate * dt).max(0.0);
            }
        }
        self.now = to;
    }

    fn log(&mut self, event: TraceEvent) {
        if self.options.trace {
            self.trace.push(event);
        }
    }

    fn record(&mut self) {
        let point = TimelinePoint {
            time: self.now,
            open: self.tasks.iter().filter(|t| t.open).count(),
            done: self.tasks.iter().filter(|t| t.done_at.is_some()).count(),
            reward: self.reward_done(),
        };
        if self.timeline.last() != Some(&point) {
            self.timeline.push(point);
        }
    }

    /// Work done on each task so far, with its task's spec.
    fn work(&self) -> impl Iterator<Item = (f64, &crate::TaskSpec)> + '_ {
        (self.tasks.iter())
            .zip(&self.mission.tasks)
            .map(|(t, spec)| (spec.workload - t.remaining, spec))
    }

    /// `Σ r_j` times the work done on each task so far.
    fn work_value(&self) -> f64 {
        self.work().map(|(w, spec)| spec.reward * w).sum()
    }

    fn reward_done(&self) -> f64 {
        self.tasks
            .iter()
            .zip(&self.mission.tasks)
            .filter(|(t, _)| t.done_at.is_some())
            .map(|(_, spec)| spec.reward * spec.workload)
            .sum()
    }
}

mod decide;
mod env;
mod finish;
mod swarm;

pub use env::{EnvStep, MissionEnv, Perception, ROBOT_FEATURES, TASK_FEATURES};
use swarm::SwarmState;
pub use swarm::{Decentralised, SwarmMetrics};

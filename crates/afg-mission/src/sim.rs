//! The event-driven simulator: exact arrival and completion times, a decision at every
//! event, any allocator in the loop.

use std::borrow::Cow;
use std::collections::{BinaryHeap, HashMap};

use afg_game::{Instance, Point, Task};

use crate::{Mission, MissionError};

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

/// The game of the robots `alive` (at `positions`) and the tasks `open` of `mission`:
/// the paper's, or GRAPE's where the mission allows idling or where the tasks cannot
/// hold every robot (the extra robots then idle); with the tasks' thresholds and
/// skills where the mission has any.
fn mission_game(
    mission: &Mission,
    alive: &[usize],
    positions: Vec<Point>,
    open: &[usize],
) -> Result<Instance, MissionError> {
    let tasks: Vec<Task> = open.iter().map(|&j| mission.tasks[j].task()).collect();
    let room = (tasks.iter())
        .map(|t| t.capacity.unwrap_or(usize::MAX))
        .fold(0usize, usize::saturating_add);
    let game = if mission.allow_void || room < positions.len() {
        Instance::with_void(positions, tasks, mission.beta)?
    } else {
        Instance::new(positions, tasks, mission.beta)?
    };
    if !mission.has_teams() {
        return Ok(game);
    }
    let s = mission.num_skills();
    let min_team = open.iter().map(|&j| mission.tasks[j].min_team).collect();
    let skills: Vec<Vec<u32>> = alive
        .iter()
        .map(|&i| mission.robots[i].skills.clone())
        .collect();
    let requires: Vec<Vec<u32>> = open
        .iter()
        .map(|&j| match &mission.tasks[j].requires {
            r if r.is_empty() => vec![0; s],
            r => r.clone(),
        })
        .collect();
    Ok(game.with_teams(min_team, &skills, &requires)?)
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
    gap: Option<f64>,
}

/// Relative tolerance under which an arrival or completion counts as reached.
const REACHED: f64 = 1e-9;

/// Runs `mission` with decisions by `replan` (see docs/missions.md for the model),
/// its options checked first.
///
/// # Errors
/// [`MissionError::Alloc`] if the allocator fails, [`MissionError::Invalid`] for an
/// option out of range.
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
pub fn simulate_with(
    mission: &Mission,
    replan: Replan<'_>,
    options: RunOptions,
    on_time: impl FnMut(f64),
) -> Result<MissionRun, MissionError> {
    check_options(&options)?;
    if let Replan::Decentralised(_) = replan {
        let central = options.replan_every.is_some()
            || options.latency != Latency::None
            || options.commit
            || options.hysteresis.is_some();
        if central {
            return Err(MissionError::Invalid(
                "replanning, latency, commitment and hysteresis are for central decisions; a decentralised method runs at its rounds per time unit".into(),
            ));
        }
    }
    run_checked(mission, replan, options, on_time)
}

/// [`simulate_with`] with options already checked (a [`Planner`](crate::Planner)'s,
/// checked once when it was made).
pub(crate) fn run_checked(
    mission: &Mission,
    replan: Replan<'_>,
    options: RunOptions,
    on_time: impl FnMut(f64),
) -> Result<MissionRun, MissionError> {
    let mut sim = Sim::new(Cow::Borrowed(mission), Some(replan), options);
    if let Replan::Decentralised(config) = replan {
        sim.swarm = Some(SwarmState::new(mission, config)?);
    }
    sim.run(on_time)?;
    Ok(sim.finish())
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
    /// The skills the robots present at each task hold together (task-major, S each).
    held: Vec<u64>,
    /// Robot-time spent at each task while its team was incomplete (missions with
    /// teams).
    waiting: Vec<f64>,
    /// The exact team solver's certified gap at each of its decisions.
    gaps: Vec<f64>,
    /// Time-ordered scheduled events: (time, kind order, what).
    scheduled: Vec<(f64, Scheduled)>,
    next_scheduled: usize,
    next_tick: Option<f64>,
    pending: Option<Pending>,
    /// An event happened while a decision was pending: decide again when it lands.
    wanted: bool,
    /// Arrivals to come: one per leg, stale once the robot's leg count moved on.
    due: BinaryHeap<Arrival>,
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
        let (m, held) = (
            mission.tasks.len(),
            mission.tasks.len() * mission.num_skills(),
        );
        Sim {
            mission,
            replan,
            options,
            now: 0.0,
            robots,
            tasks,
            held: vec![0; held],
            waiting: vec![0.0; m],
            gaps: Vec::new(),
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
            let rate = self.rate(j);
            if t.open && rate > 0.0 {
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
}

mod decide;
mod env;
mod finish;
mod motion;
mod options;
mod outcome;
mod swarm;

pub use env::{EnvStep, MissionEnv, Perception, ROBOT_FEATURES, TASK_FEATURES, TEAM_FEATURES};
use motion::Arrival;
pub use options::{Latency, Replan, RunOptions};
pub(crate) use options::{check_frame_every, check_options};
pub use outcome::{Frame, Metrics, MissionRun, TimelinePoint, TraceEvent, Waiting};
use swarm::SwarmState;
pub use swarm::{Decentralised, SwarmMetrics};

//! The exact Q\* of the sequential MDP and where a policy loses welfare.
//!
//! The reward is the welfare difference and γ = 1, so the optimal action value is an
//! optimal completion: `Q*(s_t, a) = OPT(robots before t fixed, robot t on a) − W(s_t)`
//! ([`q_star`]: one min-cost flow for all actions, [`afg_baseline::Optimum::action_values`]).
//! A policy's shortfall then telescopes over its own rollout:
//! `OPT − W(final) = Σ_t [max_a Q*(s_t, a) − Q*(s_t, a_t)]`, so each step's regret says
//! exactly where the welfare was lost ([`regret_trace`]).

use afg_baseline::Optimum;
use afg_game::{Assignment, Instance, RobotId, TaskId};
use afg_graph::RobotGraph;
use serde::Serialize;

use crate::LearnError;
use crate::fast::{FastPolicy, FastRollout};
use crate::targets::masked_argmax;

/// `Q*(s, a)` for robot `actor` acting in `assignment`, in raw welfare: for each task,
/// the best final welfare with the robots assigned in `assignment` fixed and `actor` on
/// that task, minus the welfare of `assignment`. `None` where the task has no room.
/// Where the instance allows the void task, one more value last: the actor staying out
/// (the others unassigned in `assignment` are free, as in
/// [`Optimum::complete`](afg_baseline::Optimum::complete)).
///
/// # Errors
/// [`LearnError::InvalidAction`] if the actor is already assigned or the assignment
/// does not fit the instance.
///
/// # Examples
/// ```
/// use afg_baseline::{Allocator, Optimum};
/// use afg_game::{Assignment, GeneratorConfig, RobotId};
/// use afg_learn::policy::q_star;
/// let inst = GeneratorConfig::paper(12, 3, 1).generate()?;
/// let empty = Assignment::unassigned(12, 3);
/// let q = q_star(&inst, &empty, RobotId(0))?;
/// // From the empty state, the best action value is OPT itself.
/// let best = q.iter().flatten().fold(f64::NEG_INFINITY, |a, &b| a.max(b));
/// let opt = inst.welfare(&Optimum.allocate(&inst)?.assignment);
/// assert!((best - opt).abs() < 1e-9);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn q_star(
    instance: &Instance,
    assignment: &Assignment,
    actor: RobotId,
) -> Result<Vec<Option<f64>>, LearnError> {
    if assignment.task_of(actor).is_some() {
        return Err(LearnError::InvalidAction(format!(
            "robot {actor} has already acted"
        )));
    }
    let now = instance.welfare(assignment);
    let values = Optimum
        .action_values(instance, assignment, actor)
        .map_err(|e| LearnError::InvalidAction(e.to_string()))?;
    Ok(values.into_iter().map(|v| v.map(|w| w - now)).collect())
}

/// [`q_star`] of the next robot after `prefix`, the places of robots `0..t` in the
/// sequential MDP (robots act in index order; `None`: the robot stayed out, where the
/// instance allows the void task): the values of robot `t`'s actions, one per task and,
/// where the instance allows the void, one more for staying out.
///
/// Robots that stayed out add nothing and take no room, so the values are those of the
/// game without them.
///
/// # Errors
/// [`LearnError::InvalidAction`] if every robot has acted, a task is out of range, or a
/// robot stayed out of the paper's game; the game's error for a task over its capacity.
///
/// # Examples
/// ```
/// use afg_game::{GeneratorConfig, TaskId};
/// use afg_learn::policy::{q_star, q_star_next};
/// let inst = GeneratorConfig::paper(6, 2, 1).generate()?;
/// let next = q_star_next(&inst, &[Some(TaskId(1)), Some(TaskId(0))])?;
/// assert_eq!(next.len(), 2);
/// assert!(q_star_next(&inst, &[Some(TaskId(0)); 6]).is_err()); // no robot is left
/// assert!(q_star_next(&inst, &[Some(TaskId(7))]).is_err());
/// assert!(q_star_next(&inst, &[None]).is_err()); // no void in the paper's game
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn q_star_next(
    instance: &Instance,
    prefix: &[Option<TaskId>],
) -> Result<Vec<Option<f64>>, LearnError> {
    let actor = prefix.len();
    if actor >= instance.num_robots() {
        return Err(LearnError::InvalidAction(
            "every robot has acted: there is no next robot".into(),
        ));
    }
    for (i, place) in prefix.iter().enumerate() {
        match place {
            Some(task) if task.index() >= instance.num_tasks() => {
                return Err(LearnError::InvalidAction(format!(
                    "robot {i} has task {task}, but the instance has {} tasks",
                    instance.num_tasks()
                )));
            }
            None if !instance.allows_void() => {
                return Err(LearnError::InvalidAction(format!(
                    "robot {i} stayed out, but the instance is the paper's game"
                )));
            }
            _ => {}
        }
    }
    // The game of the robots that did not stay out, the actor's index shifted.
    let stayed: Vec<usize> = (0..instance.num_robots())
        .filter(|&i| i >= actor || prefix[i].is_some())
        .collect();
    let game = if stayed.len() < instance.num_robots() {
        let robots = stayed.iter().map(|&i| instance.robots()[i]).collect();
        std::borrow::Cow::Owned(instance.with_robots(robots)?)
    } else {
        std::borrow::Cow::Borrowed(instance)
    };
    let placed: Vec<TaskId> = prefix.iter().flatten().copied().collect();
    let mut assignment = Assignment::unassigned(game.num_robots(), game.num_tasks());
    for (i, &task) in placed.iter().enumerate() {
        assignment.set(RobotId(i as u32), Some(task));
    }
    game.check(&assignment)?;
    q_star(&game, &assignment, RobotId(placed.len() as u32))
}

/// One step of a rollout, seen through Q\*.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RegretStep {
    /// Step index t (the acting robot).
    pub t: usize,
    /// The task taken.
    pub action: TaskId,
    /// `max_a Q*(s_t, a) − Q*(s_t, a_t)` ≥ 0: welfare lost at this step.
    pub regret: f64,
    /// Best minus second-best Q\* (0 with one allowed task): how much a wrong choice
    /// costs at least.
    pub gap: f64,
    /// The network's Q values of every task, in its output unit (for a network trained
    /// with reward scaling, the welfare unit of its [`Units`](afg_graph::Units):
    /// multiply by `unit` for raw welfare).
    pub q: Vec<f64>,
    /// `Q*(s_t, a)` of every task, raw welfare; `None` where the task is full.
    pub q_star: Vec<Option<f64>>,
    /// The instance's welfare unit in the network's units.
    pub unit: f64,
    /// `Q*(s_t, a_t)`.
    pub q_star_taken: f64,
}

/// A greedy rollout of `policy` (one pass per robot) with every step's Q\*.
///
/// # Errors
/// As [`FastRollout::new`].
///
/// # Complexity
/// N·M optimal completions: O(N² M³ log N). Meant for diagnosis at N ≤ a few thousand.
///
/// # Examples
/// ```
/// use afg_baseline::{Allocator, Optimum};
/// use afg_game::GeneratorConfig;
/// use afg_graph::{GraphKind, RobotGraph};
/// use afg_learn::{fast::FastPolicy, nets::NetworkConfig, policy::regret_trace};
/// let config = NetworkConfig::afgnet(5, 0);
/// let fast = FastPolicy::from_network(&config, &config.init::<afg_learn::InferBackend>(&Default::default()));
/// let inst = GeneratorConfig::paper(20, 5, 3).generate()?;
/// let graph = RobotGraph::build(inst.robots(), GraphKind::default())?;
/// let (steps, assignment) = regret_trace(&fast, &inst, &graph)?;
/// // The regrets add up to the shortfall from OPT.
/// let opt = inst.welfare(&Optimum.allocate(&inst)?.assignment);
/// let lost: f64 = steps.iter().map(|s| s.regret).sum();
/// assert!((opt - inst.welfare(&assignment) - lost).abs() < 1e-6);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn regret_trace(
    policy: &FastPolicy,
    instance: &Instance,
    graph: &RobotGraph,
) -> Result<(Vec<RegretStep>, Assignment), LearnError> {
    let m = instance.num_tasks();
    let unit = policy.units().welfare_unit(instance);
    let mut run = FastRollout::new(policy, instance, graph)?;
    let (mut q, mut mask) = (vec![0.0f32; m], vec![false; m]);
    let mut steps = Vec::with_capacity(instance.num_robots());
    for robot in instance.robot_ids() {
        run.evaluate();
        run.q_values(robot, &mut q);
        run.action_mask(robot, &mut mask);
        let action = masked_argmax(&q, &mask).ok_or_else(|| {
            LearnError::InvalidAction(format!("no task has room for robot {robot}"))
        })?;
        let star = q_star(instance, run.assignment(), robot)?;
        let mut values: Vec<f64> = star.iter().flatten().copied().collect();
        values.sort_by(|a, b| b.total_cmp(a));
        let best = values[0];
        let taken = star[action].expect("the action has room");
        let (regret, gap) = (
            (best - taken).max(0.0),
            values.get(1).map_or(0.0, |second| best - second),
        );
        steps.push(RegretStep {
            t: robot.index(),
            action: TaskId(action as u32),
            regret,
            gap,
            q: q.iter().map(|&x| f64::from(x)).collect(),
            q_star: star,
            unit,
            q_star_taken: taken,
        });
        run.assign(robot, TaskId(action as u32));
    }
    Ok((steps, run.assignment().clone()))
}

//! Honest trivial baselines: greedy, nearest, random, blind.
//!
//! Where the instance allows the void task (GRAPE's game), each has a rule for staying
//! out, given on its type: greedy and nearest when the place they would take adds
//! less than nothing, random as one more equally likely choice, and every method when
//! no task has room.
//!
//! # Complexity
//! Each is one pass over the robots that looks at every task once per robot: O(N M)
//! time and O(N + M) memory beside the assignment. Greedy and nearest place an
//! uncapped instance's robots on all cores (each robot's choice is then independent
//! of the others').

use afg_game::{Assignment, Instance, Point, TaskId};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::{AllocError, AllocStats, Allocation, Allocator, Plays, check_game, timed};

/// Robot–task pairs from which the robots of an uncapped instance are placed on all cores.
const PARALLEL_PAIRS: usize = 1 << 16;

/// Robots in index order each join the task with the best marginal welfare that has
/// room (the balanced score on the partial assignment); one pass, no revisions. Where
/// the instance allows the void task, a robot whose best marginal welfare is below 0
/// stays out.
///
/// # Examples
/// ```
/// use afg_baseline::{Allocator, Greedy};
/// let inst = afg_game::GeneratorConfig::paper(20, 5, 1).generate()?;
/// assert!(Greedy.allocate(&inst)?.assignment.is_complete());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug, Default)]
pub struct Greedy;

impl Greedy {
    /// Completes `partial`: its unassigned robots, in index order, each join the task
    /// with the best marginal welfare that has room (or stay out, see [`Greedy`]);
    /// assigned robots stay. O(N M).
    ///
    /// # Examples
    /// ```
    /// use afg_baseline::{Allocator, Greedy};
    /// use afg_game::{Assignment, GeneratorConfig};
    /// let inst = GeneratorConfig::paper(20, 5, 1).generate()?;
    /// let empty = Assignment::unassigned(20, 5);
    /// assert_eq!(Greedy.complete(&inst, &empty), Greedy.allocate(&inst)?.assignment);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn complete(&self, instance: &Instance, partial: &Assignment) -> Assignment {
        let (positions, beta) = (task_positions(instance), instance.beta());
        let mut a = partial.clone();
        // What one more member adds to each task (−∞ when full): the balanced score
        // without its travel cost. Only the joined task's entry changes per robot.
        let next = |a: &Assignment, j: TaskId| {
            if a.size(j) < instance.capacity(j) {
                instance.marginal_value(j, a.size(j) + 1)
            } else {
                f64::NEG_INFINITY
            }
        };
        let mut gain: Vec<f64> = instance.task_ids().map(|j| next(&a, j)).collect();
        for (i, &robot) in instance.robot_ids().zip(instance.robots()) {
            if a.task_of(i).is_some() {
                continue;
            }
            // As `Instance::best_response`: the first task of highest score.
            let (mut best, mut score) = (0, f64::NEG_INFINITY);
            for (j, (&g, &p)) in gain.iter().zip(&positions).enumerate() {
                let s = g - beta * robot.distance(p);
                if s > score {
                    (best, score) = (j, s);
                }
            }
            if instance.allows_void() && score < 0.0 {
                continue; // −∞ too: no task has room
            }
            let task = TaskId(best as u32);
            a.set(i, Some(task));
            gain[best] = next(&a, task);
        }
        a
    }
}

impl Allocator for Greedy {
    fn name(&self) -> String {
        "greedy".into()
    }

    fn allocate(&self, instance: &Instance) -> Result<Allocation, AllocError> {
        check_game(instance, self, Plays::Counts)?;
        let empty = Assignment::unassigned(instance.num_robots(), instance.num_tasks());
        let (assignment, wall_time) = timed(|| self.complete(instance, &empty));
        Ok(pass_allocation(instance, assignment, wall_time, None))
    }
}

/// The task positions in one contiguous array, for the loops over all N · M pairs.
pub(crate) fn task_positions(instance: &Instance) -> Vec<Point> {
    instance.tasks().iter().map(|t| t.position).collect()
}

/// Each robot, in index order, joins its nearest task that still has room. Where the
/// instance allows the void task, it stays out when that task's next member is worth
/// less than its travel cost (marginal value − β d < 0).
///
/// # Examples
/// ```
/// use afg_baseline::{Allocator, Nearest};
/// let inst = afg_game::GeneratorConfig::paper(20, 5, 1).generate()?;
/// let a = Nearest.allocate(&inst)?.assignment;
/// let i = afg_game::RobotId(0);
/// let nearest = inst.task_ids().min_by(|&x, &y| inst.distance(i, x).total_cmp(&inst.distance(i, y)));
/// assert_eq!(a.task_of(i), nearest); // no capacities here
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug, Default)]
pub struct Nearest;

impl Allocator for Nearest {
    fn name(&self) -> String {
        "nearest".into()
    }

    fn allocate(&self, instance: &Instance) -> Result<Allocation, AllocError> {
        if instance.allows_void() {
            // Staying out weighs a place's marginal value, counted by size.
            check_game(instance, self, Plays::Counts)?;
        }
        let positions = task_positions(instance);
        // The first nearest task among those `open` says have room, and its distance.
        let nearest = |robot: Point, open: &dyn Fn(usize) -> bool| {
            let (mut best, mut distance) = (None, f64::INFINITY);
            for (j, &p) in positions.iter().enumerate() {
                let d = robot.distance(p);
                if d < distance && open(j) {
                    (best, distance) = (Some(TaskId(j as u32)), d);
                }
            }
            best.map(|j| (j, distance))
        };
        let uncapped = instance
            .task_ids()
            .all(|j| instance.capacity(j) == usize::MAX);
        if !uncapped || instance.allows_void() {
            return Ok(one_pass(instance, None, |a, i| {
                let open = |j: usize| a.has_room(instance, i, TaskId(j as u32));
                let (j, d) = nearest(instance.robots()[i.index()], &open)?;
                let worth = instance.marginal_value(j, a.size(j) + 1) - instance.beta() * d;
                (!instance.allows_void() || worth >= 0.0).then_some(j)
            }));
        }
        // No capacities and no void: robots do not interact, so they are placed on all
        // cores.
        let (assignment, wall_time) = timed(|| {
            let tasks: Vec<Option<TaskId>> =
                if instance.num_robots() * positions.len() >= PARALLEL_PAIRS {
                    instance
                        .robots()
                        .par_iter()
                        .map(|&r| nearest(r, &|_| true).map(|(j, _)| j))
                        .collect()
                } else {
                    instance
                        .robots()
                        .iter()
                        .map(|&r| nearest(r, &|_| true).map(|(j, _)| j))
                        .collect()
                };
            Assignment::from_tasks(instance, tasks).expect("uncapped tasks take any robot")
        });
        Ok(pass_allocation(instance, assignment, wall_time, None))
    }
}

/// Each robot, in index order, joins a task drawn uniformly from those with room.
/// Where the instance allows the void task, the void is one more choice, as likely as
/// each task (the uniform policy over GRAPE's M + 1 actions).
///
/// # Examples
/// ```
/// use afg_baseline::{Allocator, RandomAllocator};
/// let inst = afg_game::GeneratorConfig::paper(20, 5, 1).generate()?;
/// let a = RandomAllocator { seed: 9 }.allocate(&inst)?.assignment;
/// assert_eq!(a, RandomAllocator { seed: 9 }.allocate(&inst)?.assignment);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug, Default)]
pub struct RandomAllocator {
    /// Seed of the ChaCha8 generator.
    pub seed: u64,
}

impl Allocator for RandomAllocator {
    fn name(&self) -> String {
        "random".into()
    }

    fn allocate(&self, instance: &Instance) -> Result<Allocation, AllocError> {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        let mut room: Vec<Option<TaskId>> = Vec::with_capacity(instance.num_tasks() + 1);
        Ok(one_pass(instance, Some(self.seed), |a, i| {
            room.clear();
            let open = instance.task_ids().filter(|&j| a.has_room(instance, i, j));
            room.extend(open.map(Some));
            if instance.allows_void() {
                room.push(None);
            }
            room[rng.random_range(0..room.len())]
        }))
    }
}

/// Each robot, in index order, joins the task with room that has the fewest robots so
/// far (the lowest index among ties): a round robin that never looks at a task's
/// position or reward.
///
/// It is the yardstick for policies that cannot see the tasks, such as the paper's S2V
/// network (it reads only which task each robot joined and robot-to-robot distances).
/// When the task positions are independent of the robots' and the task rewards are
/// exchangeable, a choice that ignores them leaves every robot's expected distance
/// unchanged, so in expectation over instances only the coalition sizes matter, and
/// the concave `F_j` is best served by equal sizes: no blind policy beats this one on
/// average. O(N M). Where the instance allows the void task, a robot stays out only
/// when no task has room.
///
/// # Examples
/// ```
/// use afg_baseline::{Allocator, Blind};
/// use afg_game::TaskId;
/// let inst = afg_game::GeneratorConfig::paper(7, 3, 1).generate()?;
/// let a = Blind.allocate(&inst)?.assignment;
/// let tasks: Vec<u32> = a.tasks().iter().map(|t| t.unwrap().0).collect();
/// assert_eq!(tasks, [0, 1, 2, 0, 1, 2, 0]);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug, Default)]
pub struct Blind;

impl Allocator for Blind {
    fn name(&self) -> String {
        "blind".into()
    }

    fn allocate(&self, instance: &Instance) -> Result<Allocation, AllocError> {
        Ok(one_pass(instance, None, |a, i| {
            instance
                .task_ids()
                .filter(|&j| a.has_room(instance, i, j))
                .min_by_key(|&j| a.size(j))
        }))
    }
}

/// Assigns robots in index order to `choose`'s task (`None`: the void); one iteration
/// per robot.
fn one_pass(
    instance: &Instance,
    seed: Option<u64>,
    mut choose: impl FnMut(&Assignment, afg_game::RobotId) -> Option<TaskId>,
) -> Allocation {
    let (assignment, wall_time) = timed(|| {
        let mut a = Assignment::unassigned(instance.num_robots(), instance.num_tasks());
        for i in instance.robot_ids() {
            let task = choose(&a, i);
            debug_assert!(
                task.is_some() || instance.allows_void(),
                "capacities hold every robot"
            );
            a.set(i, task);
        }
        a
    });
    pass_allocation(instance, assignment, wall_time, seed)
}

/// The allocation of a one-pass method: every robot placed once, in one sweep.
fn pass_allocation(
    instance: &Instance,
    assignment: Assignment,
    wall_time: std::time::Duration,
    seed: Option<u64>,
) -> Allocation {
    let n = instance.num_robots() as u64;
    Allocation {
        assignment,
        stats: AllocStats {
            iterations: n,
            rounds: 1,
            wall_time,
            seed,
            ..AllocStats::default()
        },
    }
}

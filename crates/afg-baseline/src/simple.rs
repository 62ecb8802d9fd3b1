//! Honest trivial baselines: greedy, nearest, random, blind.

use afg_game::{Assignment, Instance, Preference, TaskId};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::{AllocError, AllocStats, Allocation, Allocator, timed};

/// Robots in index order each join the task with the best marginal welfare that has
/// room (the balanced score on the partial assignment); one pass, no revisions.
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
    /// with the best marginal welfare that has room; assigned robots stay. O(N M).
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
        let mut a = partial.clone();
        for i in instance.robot_ids() {
            if a.task_of(i).is_none() {
                let task = instance.best_response(&a, i, Preference::Balanced);
                a.set(i, task);
            }
        }
        a
    }
}

impl Allocator for Greedy {
    fn name(&self) -> String {
        "greedy".into()
    }

    fn allocate(&self, instance: &Instance) -> Result<Allocation, AllocError> {
        Ok(one_pass(instance, None, |a, i| {
            instance.best_response(a, i, Preference::Balanced)
        }))
    }
}

/// Each robot, in index order, joins its nearest task that still has room.
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
        Ok(one_pass(instance, None, |a, i| {
            instance
                .task_ids()
                .filter(|&j| a.has_room(instance, i, j))
                .min_by(|&x, &y| instance.distance(i, x).total_cmp(&instance.distance(i, y)))
        }))
    }
}

/// Each robot, in index order, joins a task drawn uniformly from those with room.
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
        let mut room: Vec<TaskId> = Vec::with_capacity(instance.num_tasks());
        Ok(one_pass(instance, Some(self.seed), |a, i| {
            room.clear();
            room.extend(instance.task_ids().filter(|&j| a.has_room(instance, i, j)));
            Some(room[rng.random_range(0..room.len())])
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
/// average. O(N M).
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

/// Assigns robots in index order to `choose`'s task; one iteration per robot.
fn one_pass(
    instance: &Instance,
    seed: Option<u64>,
    mut choose: impl FnMut(&Assignment, afg_game::RobotId) -> Option<TaskId>,
) -> Allocation {
    let (assignment, wall_time) = timed(|| {
        let mut a = Assignment::unassigned(instance.num_robots(), instance.num_tasks());
        for i in instance.robot_ids() {
            let task = choose(&a, i);
            debug_assert!(task.is_some(), "capacities hold every robot");
            a.set(i, task);
        }
        a
    });
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

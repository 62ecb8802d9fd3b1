//! The optimum kept through events: the solver's residual state (costs, assignment,
//! counts, prices and the movers between tasks) stays in memory, and an event touches
//! what it changes — one cost column for a task that appears, the members of a task
//! that is done, the robots that fail — before the imbalance it leaves is routed.
//!
//! Each change keeps the solver's invariant (every robot at a minimum of
//! `c_ij − π_j`, every count what its price buys, up to the imbalances still to route):
//! - a task that appears gets the price at which the robots that prefer it about fill
//!   the count it buys; those robots move in, and no other robot prefers it;
//! - the members of a task that is done move to their cheapest other task;
//! - a robot that fails is one unit less for the sink, a robot that joins one more,
//!   placed at its cheapest task.
//!
//! Then successive shortest paths route what is out of balance, as from scratch, so
//! the result is the optimum with the prices that prove it.

use afg_game::{Assignment, Instance, Point, RobotId, Task, TaskId, ValueFunction};

use super::transport::{self, Column, Flow, Slots};
use crate::AllocError;

/// The exact optimum of a game that changes by events, re-solved after each from the
/// state the last solve left: tasks appear and are done, robots fail and join. After
/// every change [`IncrementalOptimum::assignment`] is the optimum of the game
/// [`IncrementalOptimum::instance`] describes, and [`IncrementalOptimum::prices`]
/// prove it ([`verify_optimal`](super::verify_optimal)).
///
/// An event costs what it changes (a cost column, the robots concerned) plus the units
/// it leaves to route, instead of the O(N M) of a solve from scratch. Memory: the
/// O(N M) costs and the solver's heaps, kept; it grows with every robot that moves (a
/// stale heap entry each until it surfaces) and every robot removed (its row stays), so
/// a long-lived solver is best rebuilt now and then:
/// `IncrementalOptimum::new(&opt.instance()?)`.
///
/// # Examples
/// ```
/// use afg_baseline::{IncrementalOptimum, Optimum, verify_optimal};
/// use afg_game::{GeneratorConfig, RobotId, TaskId};
/// let inst = GeneratorConfig::paper(300, 6, 1).generate()?;
/// let mut opt = IncrementalOptimum::new(&inst);
/// let new_task = GeneratorConfig::paper(300, 7, 2).generate()?.tasks()[6];
/// opt.add_task(new_task)?; // TaskId(6)
/// opt.remove_task(TaskId(0))?; // the others move down one
/// opt.remove_robots(&[RobotId(3), RobotId(10)])?;
/// let game = opt.instance()?;
/// assert_eq!((game.num_robots(), game.num_tasks()), (298, 6));
/// let proof = verify_optimal(&game, &opt.assignment(), &opt.prices())?;
/// let (scratch, _) = Optimum.with_prices(&game);
/// assert!((proof.welfare - game.welfare(&scratch)).abs() < 1e-9 * proof.welfare.abs());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone)]
pub struct IncrementalOptimum {
    flow: Flow,
    beta: f64,
    allow_void: bool,
    /// The position of every row's robot (of robots gone too).
    positions: Vec<Point>,
    /// The task of every column: `None` for the void and closed columns.
    tasks: Vec<Option<Task>>,
    /// The row of every robot, in [`RobotId`] order.
    rows: Vec<u32>,
    /// The column of every task, in [`TaskId`] order.
    columns: Vec<u32>,
}

impl IncrementalOptimum {
    /// Solves `instance` (as [`Optimum::with_prices`](super::Optimum::with_prices)) and
    /// keeps the solver's state.
    pub fn new(instance: &Instance) -> Self {
        let spare = instance.num_tasks() / 16 + 1;
        let mut tasks: Vec<Option<Task>> = instance.tasks().iter().copied().map(Some).collect();
        tasks.resize(
            tasks.len() + usize::from(instance.allows_void()) + spare,
            None,
        );
        let mut flow = transport::solved(instance, spare);
        flow.build_movers();
        IncrementalOptimum {
            flow,
            beta: instance.beta(),
            allow_void: instance.allows_void(),
            positions: instance.robots().to_vec(),
            tasks,
            rows: (0..instance.num_robots() as u32).collect(),
            columns: (0..instance.num_tasks() as u32).collect(),
        }
    }

    /// The robots N now.
    pub fn num_robots(&self) -> usize {
        self.rows.len()
    }

    /// The tasks M now.
    pub fn num_tasks(&self) -> usize {
        self.columns.len()
    }

    /// The units the last change routed along shortest paths (the solve's work beyond
    /// the robots it touched).
    ///
    /// # Examples
    /// ```
    /// use afg_baseline::IncrementalOptimum;
    /// use afg_game::{GeneratorConfig, RobotId};
    /// let inst = GeneratorConfig::paper(400, 4, 2).generate()?;
    /// let mut opt = IncrementalOptimum::new(&inst);
    /// opt.remove_robots(&[RobotId(0)])?;
    /// assert!(opt.routed() <= 2); // one robot gone leaves little out of balance
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn routed(&self) -> u64 {
        self.flow.routed()
    }

    /// The game now: the robots in [`RobotId`] order, the tasks in [`TaskId`] order.
    ///
    /// # Errors
    /// [`AllocError::Game`] if the game has left an instance's bounds (travel costs
    /// above [`afg_game::MAX_VALUE`]).
    pub fn instance(&self) -> Result<Instance, AllocError> {
        let robots = (self.rows.iter())
            .map(|&r| self.positions[r as usize])
            .collect();
        let tasks = (self.columns.iter())
            .map(|&c| self.tasks[c as usize].expect("a task's column holds it"))
            .collect();
        Ok(if self.allow_void {
            Instance::with_void(robots, tasks, self.beta)?
        } else {
            Instance::new(robots, tasks, self.beta)?
        })
    }

    /// The optimal assignment of [`IncrementalOptimum::instance`].
    pub fn assignment(&self) -> Assignment {
        let mut task_at = vec![None; self.tasks.len()];
        for (t, &c) in self.columns.iter().enumerate() {
            task_at[c as usize] = Some(TaskId(t as u32));
        }
        let mut a = Assignment::unassigned(self.num_robots(), self.num_tasks());
        let task_of = self.flow.task_of();
        for (i, &r) in self.rows.iter().enumerate() {
            a.set(RobotId(i as u32), task_at[task_of[r as usize] as usize]);
        }
        a
    }

    /// The task prices that prove [`IncrementalOptimum::assignment`] optimal, one per
    /// task (measured from the void's 0 where the game allows it).
    pub fn prices(&self) -> Vec<f64> {
        let prices = self.flow.prices();
        self.columns.iter().map(|&c| prices[c as usize]).collect()
    }

    /// A task appears; it takes the next [`TaskId`]. Re-solves.
    ///
    /// # Errors
    /// [`AllocError::Game`] if `task` is not a valid task (a non-finite position, a
    /// reward out of range, eps below φ), [`AllocError::InvalidParameter`] if a robot's
    /// travel cost to it is not finite.
    pub fn add_task(&mut self, task: Task) -> Result<TaskId, AllocError> {
        Instance::with_void(vec![task.position], vec![task], self.beta)?;
        let costs: Vec<f64> = (self.positions.iter())
            .map(|p| self.beta * p.distance(task.position))
            .collect();
        if costs.iter().any(|c| !c.is_finite()) {
            return Err(AllocError::InvalidParameter(
                "the new task is too far from the robots for finite travel costs".into(),
            ));
        }
        let column = Column::Task {
            value: Slots::concave(ValueFunction::of(&task)),
            capacity: task.capacity.unwrap_or(usize::MAX),
        };
        let c = self.flow.open(column, &costs);
        self.tasks.resize(self.flow.columns().len(), None);
        self.tasks[c] = Some(task);
        self.columns.push(c as u32);
        self.resolve();
        Ok(TaskId(self.columns.len() as u32 - 1))
    }

    /// Task `task` is done (or withdrawn): it leaves the game, and the tasks after it
    /// move down one [`TaskId`]. Re-solves.
    ///
    /// # Errors
    /// [`AllocError::InvalidParameter`] if `task` is not a task of the game, is its
    /// last, or (in the paper's game) the other tasks' capacities cannot hold every
    /// robot.
    pub fn remove_task(&mut self, task: TaskId) -> Result<(), AllocError> {
        let t = task.index();
        if t >= self.num_tasks() || self.num_tasks() == 1 {
            return Err(AllocError::InvalidParameter(format!(
                "task {task} is not a task of the game, or is its last ({} tasks)",
                self.num_tasks()
            )));
        }
        let others = (self.columns.iter().enumerate())
            .filter(|&(u, _)| u != t)
            .map(|(_, &c)| self.capacity(c))
            .fold(0, usize::saturating_add);
        self.check_room(others, self.num_robots())?;
        let c = self.columns.remove(t) as usize;
        self.tasks[c] = None;
        self.flow.close(c);
        self.resolve();
        Ok(())
    }

    /// Robots fail (or are withdrawn): they leave the game, and the others keep their
    /// order, moving down in [`RobotId`]. Re-solves.
    ///
    /// # Errors
    /// [`AllocError::InvalidParameter`] if a robot is not in the game, is named twice,
    /// or if no robot would be left.
    pub fn remove_robots(&mut self, robots: &[RobotId]) -> Result<(), AllocError> {
        let n = self.num_robots();
        let mut gone = vec![false; n];
        for &r in robots {
            if r.index() >= n || std::mem::replace(&mut gone[r.index()], true) {
                return Err(AllocError::InvalidParameter(format!(
                    "robot {r} is not in the game of {n} robots, or is named twice"
                )));
            }
        }
        if robots.len() == n {
            return Err(AllocError::InvalidParameter(
                "a game needs a robot: all would be removed".into(),
            ));
        }
        for &r in robots {
            self.flow.remove_robot(self.rows[r.index()] as usize);
        }
        let mut index = 0;
        self.rows.retain(|_| {
            index += 1;
            !gone[index - 1]
        });
        self.resolve();
        Ok(())
    }

    /// Robots join at `positions`; they take the next [`RobotId`]s. Re-solves.
    ///
    /// # Errors
    /// [`AllocError::InvalidParameter`] if a position or a travel cost is not finite,
    /// or (in the paper's game) the tasks' capacities cannot hold every robot.
    ///
    /// # Examples
    /// ```
    /// use afg_baseline::{IncrementalOptimum, Optimum};
    /// use afg_game::{GeneratorConfig, Point};
    /// let inst = GeneratorConfig::paper(50, 3, 4).generate()?;
    /// let mut opt = IncrementalOptimum::new(&inst);
    /// opt.add_robots(&[Point::new(0.5, 0.5), Point::new(0.1, 0.9)])?; // RobotIds 50 and 51
    /// let game = opt.instance()?;
    /// let (scratch, _) = Optimum.with_prices(&game);
    /// assert!((game.welfare(&opt.assignment()) - game.welfare(&scratch)).abs() < 1e-9);
    /// // A position that is not a point is refused, and nothing changes.
    /// assert!(opt.add_robots(&[Point::new(f64::NAN, 0.0)]).is_err());
    /// assert_eq!(opt.num_robots(), 52);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn add_robots(&mut self, positions: &[Point]) -> Result<(), AllocError> {
        let room = (self.columns.iter())
            .map(|&c| self.capacity(c))
            .fold(0, usize::saturating_add);
        self.check_room(room, self.num_robots() + positions.len())?;
        let rows: Vec<Vec<f64>> = positions.iter().map(|&p| self.costs(p)).collect();
        if let Some(i) = (0..positions.len()).find(|&i| rows[i].iter().any(|c| !c.is_finite())) {
            return Err(AllocError::InvalidParameter(format!(
                "robot at {:?} has a travel cost that is not finite",
                positions[i]
            )));
        }
        for (&p, costs) in positions.iter().zip(&rows) {
            let row = self.flow.add_robot(costs);
            self.positions.push(p);
            self.rows.push(row as u32);
        }
        self.resolve();
        Ok(())
    }

    /// Back to the optimum after a change: the sink's potential rebalanced, then what
    /// is still out of balance routed.
    fn resolve(&mut self) {
        self.flow.rebalance();
        self.flow.route();
    }

    /// The travel costs of a robot at `p` to every column (0 to the void and to closed
    /// columns).
    fn costs(&self, p: Point) -> Vec<f64> {
        (self.tasks.iter())
            .map(|t| t.map_or(0.0, |t| self.beta * p.distance(t.position)))
            .collect()
    }

    /// The capacity of column `c`'s task.
    fn capacity(&self, c: u32) -> usize {
        (self.tasks[c as usize]).map_or(0, |t| t.capacity.unwrap_or(usize::MAX))
    }

    /// In the paper's game, tasks with room for `room` robots must hold `robots`.
    fn check_room(&self, room: usize, robots: usize) -> Result<(), AllocError> {
        if !self.allow_void && room < robots {
            return Err(AllocError::InvalidParameter(format!(
                "the tasks would have room for {room} robots, fewer than the {robots} in the paper's game (which has no void task)"
            )));
        }
        Ok(())
    }
}

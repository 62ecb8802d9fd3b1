//! Problem instances: robots, tasks, the coalition value F_j and the utility u_i (paper eq. 2).

use serde::{Deserialize, Serialize};

use crate::{GameError, GeneratorConfig, RobotId, TaskId};

/// The golden ratio φ = (1 + √5) / 2: the smallest `eps` for which F_j is concave in n.
pub const GOLDEN_RATIO: f64 = 1.618_033_988_749_895;

/// The largest reward, and the largest travel cost β · d, that an instance may hold.
///
/// Far beyond any real mission, and small enough that a welfare summed over 2^32
/// robots stays finite and that the optimum's exact comparisons keep their precision.
pub const MAX_VALUE: f64 = 1e15;

/// A point in the plane (the paper uses the unit square, but any finite point is allowed).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Point {
    /// x coordinate.
    pub x: f64,
    /// y coordinate.
    pub y: f64,
}

impl Point {
    /// A point from its coordinates.
    pub const fn new(x: f64, y: f64) -> Self {
        Point { x, y }
    }

    /// Euclidean distance to `other`: `sqrt(dx² + dy²)`, which vectorises (`hypot` does
    /// not, and costs several times more in the loops over all N · M pairs). It cannot
    /// overflow in an [`Instance`], whose extent is checked finite.
    ///
    /// # Examples
    /// ```
    /// use afg_game::Point;
    /// assert_eq!(Point::new(0.0, 0.0).distance(Point::new(3.0, 4.0)), 5.0);
    /// ```
    #[inline]
    pub fn distance(self, other: Point) -> f64 {
        let (dx, dy) = (self.x - other.x, self.y - other.y);
        (dx * dx + dy * dy).sqrt()
    }

    /// Whether both coordinates are finite.
    ///
    /// # Examples
    /// ```
    /// use afg_game::Point;
    /// assert!(Point::new(1.0, 2.0).is_finite() && !Point::new(f64::NAN, 0.0).is_finite());
    /// ```
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite()
    }
}

/// The diagonal of the bounding box of `points`: no two of them are further apart.
fn extent<'a>(points: impl Iterator<Item = &'a Point>) -> f64 {
    let mut lo = Point::new(f64::INFINITY, f64::INFINITY);
    let mut hi = Point::new(f64::NEG_INFINITY, f64::NEG_INFINITY);
    for p in points {
        lo = Point::new(lo.x.min(p.x), lo.y.min(p.y));
        hi = Point::new(hi.x.max(p.x), hi.y.max(p.y));
    }
    lo.distance(hi)
}

/// A task: where it is, what it pays, how its value grows with the coalition.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Task {
    /// Location.
    pub position: Point,
    /// Initial reward `r_j`: the value of a coalition of one robot, F_j(1).
    pub reward: f64,
    /// Base `eps_j` of the logarithm in F_j; must be at least the golden ratio.
    pub eps: f64,
    /// Largest coalition the task accepts (the paper's h̄_j); `None` means unbounded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub capacity: Option<usize>,
}

/// A task's coalition value `F(n) = r log_eps(n + eps − 1)`, with `1 / ln(eps)` kept
/// because it is evaluated in every inner loop. The one definition of the game's
/// values: [`Instance::coalition_value`] and [`Instance::marginal_value`] read it.
///
/// # Examples
/// ```
/// use afg_game::{Point, Task, ValueFunction};
/// let task = Task { position: Point::new(0.0, 0.0), reward: 3.0, eps: 2.0, capacity: None };
/// let f = ValueFunction::of(&task);
/// assert_eq!(f.value(0), 0.0);
/// assert!((f.value(3) - 6.0).abs() < 1e-12); // eps = 2: F(3) = r log2(4) = 2r
/// assert!((f.marginal(3) - (f.value(3) - f.value(2))).abs() < 1e-12);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ValueFunction {
    reward: f64,
    eps: f64,
    inv_ln_eps: f64,
}

impl ValueFunction {
    /// The value function of `task`.
    pub fn of(task: &Task) -> Self {
        ValueFunction {
            reward: task.reward,
            eps: task.eps,
            inv_ln_eps: 1.0 / task.eps.ln(),
        }
    }

    /// `F(n)`, with `F(0) = 0`.
    #[inline]
    pub fn value(&self, n: usize) -> f64 {
        if n == 0 {
            return 0.0;
        }
        self.reward * (n as f64 + self.eps - 1.0).ln() * self.inv_ln_eps
    }

    /// The marginal value of the n-th member, `F(n) − F(n − 1)` (n ≥ 1); decreasing in n.
    #[inline]
    pub fn marginal(&self, n: usize) -> f64 {
        debug_assert!(n >= 1);
        if n == 1 {
            return self.reward;
        }
        // log((n + eps - 1) / (n + eps - 2)) loses less precision than a difference of logs.
        self.reward * (1.0 / (n as f64 + self.eps - 2.0)).ln_1p() * self.inv_ln_eps
    }
}

/// One game: N robots, M tasks, the distance penalty beta.
///
/// Built only through [`Instance::new`] (or deserialisation, which calls it),
/// so every `Instance` is valid: N ≥ 1, M ≥ 1, finite coordinates, rewards ≥ 0,
/// eps ≥ φ, beta ≥ 0 and capacities that can hold all robots.
///
/// # Examples
/// ```
/// use afg_game::{Instance, Point, Task, TaskId};
/// let task = Task { position: Point::new(0.0, 0.0), reward: 2.0, eps: 2.0, capacity: None };
/// let inst = Instance::new(vec![Point::new(0.0, 1.0)], vec![task], 1.0)?;
/// // F(1) = r, and one robot at distance 1 gets 2 - 1.
/// assert_eq!(inst.coalition_value(TaskId(0), 1), 2.0);
/// assert_eq!(inst.utility(0.into(), TaskId(0), 1), 1.0);
/// # Ok::<(), afg_game::GameError>(())
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "crate::io::InstanceFile", into = "crate::io::InstanceFile")]
pub struct Instance {
    robots: Vec<Point>,
    tasks: Vec<Task>,
    beta: f64,
    generator: Option<GeneratorConfig>,
    /// Whether robots may join the void task (GRAPE's game).
    allow_void: bool,
    /// F_j of every task.
    values: Vec<ValueFunction>,
    /// Thresholds and skills (none in the paper's game).
    pub(crate) teams: crate::teams::TeamRules,
}

impl Instance {
    /// Validates and builds an instance.
    ///
    /// # Errors
    /// [`GameError::NoRobots`], [`GameError::NoTasks`],
    /// [`GameError::NonFiniteCoordinate`], [`GameError::InvalidReward`],
    /// [`GameError::EpsBelowGoldenRatio`], [`GameError::InvalidBeta`],
    /// [`GameError::CostTooLarge`] (β times the extent of the points above
    /// [`MAX_VALUE`]) or [`GameError::CapacityTooSmall`].
    pub fn new(robots: Vec<Point>, tasks: Vec<Task>, beta: f64) -> Result<Self, GameError> {
        Self::build(robots, tasks, beta, false)
    }

    /// The same game in GRAPE's wider form: a robot may join the **void task** (no
    /// task at all, utility 0) instead of a coalition, so total capacity may be below
    /// N and robots for whom every task would be a loss may stay out. The paper's game
    /// ([`Instance::new`]) puts every robot in a coalition.
    ///
    /// # Errors
    /// As [`Instance::new`], but for [`GameError::CapacityTooSmall`].
    ///
    /// # Examples
    /// ```
    /// use afg_game::{Instance, Point, Task};
    /// let robots = vec![Point::new(0.0, 0.0), Point::new(9.0, 0.0)];
    /// let task = Task { position: Point::new(0.0, 0.0), reward: 1.0, eps: 2.0, capacity: Some(1) };
    /// assert!(Instance::new(robots.clone(), vec![task.clone()], 1.0).is_err()); // room for one of two
    /// let inst = Instance::with_void(robots, vec![task], 1.0)?;
    /// assert!(inst.allows_void());
    /// # Ok::<(), afg_game::GameError>(())
    /// ```
    pub fn with_void(robots: Vec<Point>, tasks: Vec<Task>, beta: f64) -> Result<Self, GameError> {
        Self::build(robots, tasks, beta, true)
    }

    fn build(
        robots: Vec<Point>,
        tasks: Vec<Task>,
        beta: f64,
        allow_void: bool,
    ) -> Result<Self, GameError> {
        if robots.is_empty() {
            return Err(GameError::NoRobots);
        }
        if tasks.is_empty() {
            return Err(GameError::NoTasks);
        }
        if u32::try_from(robots.len()).is_err() || u32::try_from(tasks.len()).is_err() {
            return Err(GameError::InvalidGenerator(
                "at most 2^32 - 1 robots and tasks".into(),
            ));
        }
        for (index, p) in robots.iter().enumerate() {
            if !p.is_finite() {
                return Err(GameError::NonFiniteCoordinate {
                    what: "robot",
                    index,
                    x: p.x,
                    y: p.y,
                });
            }
        }
        for (index, t) in tasks.iter().enumerate() {
            let p = t.position;
            if !p.is_finite() {
                return Err(GameError::NonFiniteCoordinate {
                    what: "task",
                    index,
                    x: p.x,
                    y: p.y,
                });
            }
            if !(t.reward.is_finite() && (0.0..=MAX_VALUE).contains(&t.reward)) {
                return Err(GameError::InvalidReward {
                    task: index,
                    reward: t.reward,
                });
            }
            // `!(>=)` also rejects NaN.
            if !(t.eps >= GOLDEN_RATIO && t.eps.is_finite()) {
                return Err(GameError::EpsBelowGoldenRatio {
                    task: index,
                    eps: t.eps,
                });
            }
        }
        if !(beta.is_finite() && beta >= 0.0) {
            return Err(GameError::InvalidBeta(beta));
        }
        let extent = extent(robots.iter().chain(tasks.iter().map(|t| &t.position)));
        if !(beta * extent).is_finite() || beta * extent > MAX_VALUE {
            return Err(GameError::CostTooLarge {
                beta,
                extent,
                limit: MAX_VALUE,
            });
        }
        if !allow_void && tasks.iter().all(|t| t.capacity.is_some()) {
            let total = tasks
                .iter()
                .map(|t| t.capacity.unwrap_or(0))
                .fold(0usize, usize::saturating_add);
            if total < robots.len() {
                return Err(GameError::CapacityTooSmall {
                    total,
                    robots: robots.len(),
                });
            }
        }
        let values = tasks.iter().map(ValueFunction::of).collect();
        Ok(Instance {
            robots,
            tasks,
            beta,
            generator: None,
            allow_void,
            values,
            teams: Default::default(),
        })
    }

    /// The same game — tasks, β, the void option and the tasks' thresholds — with other
    /// robots (survivors, newcomers, robots that have moved). The generator record is
    /// not kept.
    ///
    /// # Errors
    /// As [`Instance::new`] (or [`Instance::with_void`]) for the new robots, and
    /// [`GameError::SkillsOfNewRobots`] in a game with skills (the new robots' skills
    /// are unknown).
    ///
    /// # Examples
    /// ```
    /// use afg_game::{Instance, Point, Task};
    /// let task = Task { position: Point::new(0.0, 0.0), reward: 1.0, eps: 2.0, capacity: Some(1) };
    /// let inst = Instance::with_void(vec![Point::new(1.0, 0.0)], vec![task], 1.0)?;
    /// let more = inst.with_robots(vec![Point::new(1.0, 0.0), Point::new(2.0, 0.0)])?;
    /// assert!(more.allows_void() && more.num_robots() == 2);
    /// # Ok::<(), afg_game::GameError>(())
    /// ```
    pub fn with_robots(&self, robots: Vec<Point>) -> Result<Self, GameError> {
        if self.num_skills() > 0 {
            return Err(GameError::SkillsOfNewRobots);
        }
        let mut instance = Self::build(robots, self.tasks.clone(), self.beta, self.allow_void)?;
        instance.teams.min_team = self.teams.min_team.clone();
        Ok(instance)
    }

    /// The same game with some of its own robots, `kept` (in that order), now at
    /// `points` (survivors, robots that have moved): their skills, the tasks'
    /// thresholds and requirements kept. The generator record is not kept.
    ///
    /// # Errors
    /// As [`Instance::new`] for the new positions, and [`GameError::TeamListLength`]
    /// where `kept` and `points` differ in length.
    ///
    /// # Panics
    /// If `kept` names a robot not in the game.
    ///
    /// # Examples
    /// ```
    /// use afg_game::{Instance, Point, RobotId, Task};
    /// let task = Task { position: Point::new(0.0, 0.0), reward: 1.0, eps: 2.0, capacity: None };
    /// let robots = vec![Point::new(1.0, 0.0), Point::new(2.0, 0.0)];
    /// let inst = Instance::new(robots, vec![task], 1.0)?.with_teams(vec![1], &[vec![0], vec![1]], &[vec![1]])?;
    /// let moved = inst.with_robots_at(&[RobotId(1)], vec![Point::new(0.5, 0.0)])?;
    /// assert_eq!((moved.num_robots(), moved.skills(RobotId(0))), (1, &[1][..]));
    /// # Ok::<(), afg_game::GameError>(())
    /// ```
    pub fn with_robots_at(&self, kept: &[RobotId], points: Vec<Point>) -> Result<Self, GameError> {
        if kept.len() != points.len() {
            return Err(GameError::TeamListLength {
                what: "the robots kept",
                len: kept.len(),
                expected: points.len(),
            });
        }
        let instance = Self::build(points, self.tasks.clone(), self.beta, self.allow_void)?;
        if !self.has_teams() {
            return Ok(instance);
        }
        let skills: Vec<Vec<u32>> = kept.iter().map(|&i| self.skills(i).to_vec()).collect();
        let requires: Vec<Vec<u32>> = self.task_ids().map(|j| self.requires(j).to_vec()).collect();
        let min_team = self.task_ids().map(|j| self.min_team(j)).collect();
        instance.with_teams(min_team, &skills, &requires)
    }

    /// Records the generator parameters that produced this instance.
    pub fn with_generator(mut self, generator: GeneratorConfig) -> Self {
        self.generator = Some(generator);
        self
    }

    /// Whether a robot may join the void task (GRAPE's game, [`Instance::with_void`]);
    /// `false` for the paper's game, where every robot joins a coalition.
    #[inline]
    pub fn allows_void(&self) -> bool {
        self.allow_void
    }

    /// Number of robots N.
    #[inline]
    pub fn num_robots(&self) -> usize {
        self.robots.len()
    }

    /// Number of tasks M.
    #[inline]
    pub fn num_tasks(&self) -> usize {
        self.tasks.len()
    }

    /// Robot positions, indexed by [`RobotId`].
    pub fn robots(&self) -> &[Point] {
        &self.robots
    }

    /// The tasks, indexed by [`TaskId`].
    pub fn tasks(&self) -> &[Task] {
        &self.tasks
    }

    /// One task.
    #[inline]
    pub fn task(&self, task: TaskId) -> &Task {
        &self.tasks[task.index()]
    }

    /// The distance penalty beta.
    pub fn beta(&self) -> f64 {
        self.beta
    }

    /// The generator parameters, if this instance was generated.
    pub fn generator(&self) -> Option<&GeneratorConfig> {
        self.generator.as_ref()
    }

    /// All robot ids, `0..N`.
    pub fn robot_ids(&self) -> impl ExactSizeIterator<Item = RobotId> + use<> {
        (0..self.robots.len() as u32).map(RobotId)
    }

    /// All task ids, `0..M`.
    pub fn task_ids(&self) -> impl ExactSizeIterator<Item = TaskId> + use<> {
        (0..self.tasks.len() as u32).map(TaskId)
    }

    /// Capacity of a task; `usize::MAX` when unbounded.
    #[inline]
    pub fn capacity(&self, task: TaskId) -> usize {
        self.tasks[task.index()].capacity.unwrap_or(usize::MAX)
    }

    /// Euclidean distance d(i, j) from a robot to a task.
    #[inline]
    pub fn distance(&self, robot: RobotId, task: TaskId) -> f64 {
        self.robots[robot.index()].distance(self.tasks[task.index()].position)
    }

    /// Travel cost beta * d(i, j).
    #[inline]
    pub fn cost(&self, robot: RobotId, task: TaskId) -> f64 {
        self.beta * self.distance(robot, task)
    }

    /// Coalition value `F_j(n) = r_j log_{eps_j}(n + eps_j - 1)`, with `F_j(0) = 0`,
    /// and 0 below the task's threshold ([`Instance::min_team`]). In a game with skill
    /// rules ([`Instance::has_skill_rules`]) a coalition also needs its skills: see
    /// [`Instance::welfare`].
    ///
    /// # Examples
    /// ```
    /// # use afg_game::{Instance, Point, Task, TaskId};
    /// # let task = Task { position: Point::new(0.0, 0.0), reward: 3.0, eps: 2.0, capacity: None };
    /// # let inst = Instance::new(vec![Point::new(0.0, 0.0)], vec![task], 1.0).unwrap();
    /// // eps = 2: F(3) = r log2(4) = 2r.
    /// assert!((inst.coalition_value(TaskId(0), 3) - 6.0).abs() < 1e-12);
    /// ```
    #[inline]
    pub fn coalition_value(&self, task: TaskId, n: usize) -> f64 {
        if n < self.min_team(task) {
            return 0.0;
        }
        self.values[task.index()].value(n)
    }

    /// Marginal value of the n-th member, `F_j(n) - F_j(n - 1)` (n ≥ 1) of
    /// [`Instance::coalition_value`]: decreasing in n without a threshold; with one
    /// (k > 1), 0 below k and the whole `F_j(k)` at k.
    #[inline]
    pub fn marginal_value(&self, task: TaskId, n: usize) -> f64 {
        let k = self.min_team(task);
        match n.cmp(&k) {
            std::cmp::Ordering::Less => 0.0,
            std::cmp::Ordering::Equal if k > 1 => self.values[task.index()].value(n),
            _ => self.values[task.index()].marginal(n),
        }
    }

    /// F_j of a task, concave, without its threshold.
    #[inline]
    pub fn value_function(&self, task: TaskId) -> ValueFunction {
        self.values[task.index()]
    }

    /// Utility of robot i in a coalition of size n at task j (paper eq. 2):
    /// `u_i(j, n) = F_j(n) / n - beta d(i, j)`, for n ≥ 1.
    #[inline]
    pub fn utility(&self, robot: RobotId, task: TaskId, n: usize) -> f64 {
        debug_assert!(n >= 1);
        self.coalition_value(task, n) / n as f64 - self.cost(robot, task)
    }
}

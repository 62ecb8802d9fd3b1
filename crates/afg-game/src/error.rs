//! The one error type of the game crate.

use thiserror::Error;

/// Everything that can be wrong with an instance, an assignment or a file.
///
/// Every constructor and reader of this crate validates its input and
/// returns one of these instead of panicking or computing a wrong answer.
#[derive(Debug, Error)]
pub enum GameError {
    /// The instance has no robots.
    #[error("an instance needs at least one robot (N = 0)")]
    NoRobots,
    /// The instance has no tasks.
    #[error("an instance needs at least one task (M = 0)")]
    NoTasks,
    /// A coordinate is NaN or infinite.
    #[error("{what} {index} has a non-finite coordinate ({x}, {y})")]
    NonFiniteCoordinate {
        /// "robot" or "task".
        what: &'static str,
        /// Index of the offending robot or task.
        index: usize,
        /// The x coordinate as given.
        x: f64,
        /// The y coordinate as given.
        y: f64,
    },
    /// A task's base eps is below the golden ratio, so F_j is not concave.
    #[error(
        "task {task} has eps = {eps}, below the golden ratio 1.618…: the coalition value \
         would not be concave, and stability and the exact optimum rely on that"
    )]
    EpsBelowGoldenRatio {
        /// The task.
        task: usize,
        /// Its eps.
        eps: f64,
    },
    /// A task's initial reward is negative or not finite.
    #[error(
        "task {task} has reward {reward}: rewards must be between 0 and 1e15 (afg_game::MAX_VALUE)"
    )]
    InvalidReward {
        /// The task.
        task: usize,
        /// Its reward.
        reward: f64,
    },
    /// The distance penalty beta is negative or not finite.
    #[error("beta = {0}: the distance penalty must be finite and non-negative")]
    InvalidBeta(f64),
    /// Travel costs would be too large to compute with: β times the largest distance
    /// between two of the instance's points exceeds the limit.
    #[error(
        "beta = {beta} times the instance's extent {extent} (the diagonal of the box around \
         its robots and tasks) exceeds {limit:e}: travel costs must stay below that limit"
    )]
    CostTooLarge {
        /// The distance penalty.
        beta: f64,
        /// The diagonal of the bounding box of all points.
        extent: f64,
        /// [`crate::MAX_VALUE`].
        limit: f64,
    },
    /// The capacities cannot hold every robot.
    #[error("task capacities sum to {total}, fewer than the {robots} robots to assign")]
    CapacityTooSmall {
        /// Sum of all capacities.
        total: usize,
        /// Number of robots.
        robots: usize,
    },
    /// A task's `min_team` is 0.
    #[error("task {task} has min_team 0: a threshold is a whole number of robots, at least 1")]
    InvalidMinTeam {
        /// The task.
        task: usize,
    },
    /// A count in a file (`min_team`, `capacity`, `skills`, `requires`) that is not a
    /// whole number in range.
    #[error("{what} {index}: {field} must be a whole number of at least {min}, got {value}")]
    InvalidCount {
        /// "robot" or "task".
        what: &'static str,
        /// Its index.
        index: usize,
        /// The field.
        field: &'static str,
        /// The least it may be.
        min: u32,
        /// What the file holds, as JSON.
        value: String,
    },
    /// A team list (`min_team`, `skills`, `requires`) of the wrong length.
    #[error("{what} has {len} entries, but the instance has {expected}")]
    TeamListLength {
        /// Which list.
        what: &'static str,
        /// Its length.
        len: usize,
        /// One per task (robot).
        expected: usize,
    },
    /// Two skill lists of different lengths.
    #[error(
        "{what} {index} lists {len} skills but {first} {first_index} lists {expected}: every non-empty `skills` and `requires` list must have the same length"
    )]
    SkillLength {
        /// "robot" (`skills`) or "task" (`requires`).
        what: &'static str,
        /// Its index.
        index: usize,
        /// Its length.
        len: usize,
        /// The length of the first non-empty list.
        expected: usize,
        /// What the first non-empty list belongs to.
        first: &'static str,
        /// Its index.
        first_index: usize,
    },
    /// Other robots for a game with skills, whose skills are not known.
    #[error("a game with skills cannot take other robots without their skills")]
    SkillsOfNewRobots,
    /// An assignment has a different number of entries than the instance has robots.
    #[error("assignment has {got} entries but the instance has {expected} robots")]
    AssignmentLength {
        /// Robots in the instance.
        expected: usize,
        /// Entries in the assignment.
        got: usize,
    },
    /// An assignment names a task that does not exist.
    #[error("robot {robot} is assigned to task {task}, but the instance has only {tasks} tasks")]
    TaskOutOfRange {
        /// The robot.
        robot: usize,
        /// The task it names.
        task: usize,
        /// Number of tasks.
        tasks: usize,
    },
    /// An assignment puts more robots on a task than its capacity.
    #[error("task {task} holds {size} robots, above its capacity {capacity}")]
    CapacityExceeded {
        /// The task.
        task: usize,
        /// Its coalition size.
        size: usize,
        /// Its capacity.
        capacity: usize,
    },
    /// A generator parameter is out of range.
    #[error("invalid generator parameter: {0}")]
    InvalidGenerator(String),
    /// A previous assignment that cannot be carried over to the changed instance.
    #[error("cannot carry the previous assignment over: {0}")]
    Reallocation(String),
    /// A JSON document of another kind (e.g. an assignment where an instance was expected).
    #[error("expected a JSON document of format \"{expected}\", found \"{found}\"")]
    WrongFormat {
        /// The format this reader accepts.
        expected: &'static str,
        /// The format the file declares.
        found: String,
    },
    /// A JSON document of a format version this build cannot read.
    #[error(
        "format \"{format}\" version {found} is not supported (this build reads version {supported})"
    )]
    UnsupportedVersion {
        /// The format.
        format: &'static str,
        /// The version found.
        found: u32,
        /// The version supported.
        supported: u32,
    },
    /// Malformed JSON, or JSON of the wrong shape.
    #[error("invalid JSON{}: {source}", line.map(|l| format!(" on line {l}")).unwrap_or_default())]
    Json {
        /// Line of a JSON Lines file, if the error is in one.
        line: Option<usize>,
        /// The parser's message.
        #[source]
        source: serde_json::Error,
    },
    /// A valid JSON line of a dataset that is not a valid instance.
    #[error("line {line}: {source}")]
    AtLine {
        /// Line of the JSON Lines file.
        line: usize,
        /// What is wrong with the instance on it.
        #[source]
        source: Box<GameError>,
    },
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// A name that is none of an enum's ([`crate::Named`]).
    #[error("unknown {what} {name:?}: expected {expected}")]
    UnknownName {
        /// What was named ("preference").
        what: &'static str,
        /// The name given.
        name: String,
        /// The names there are.
        expected: String,
    },
    /// An error in the named file.
    #[error("{path}: {source}")]
    InFile {
        /// The file.
        path: String,
        /// What is wrong in it.
        #[source]
        source: Box<GameError>,
    },
    /// A file of instances that holds none.
    #[error("{path} holds no instance")]
    NoInstances {
        /// The file.
        path: String,
    },
}

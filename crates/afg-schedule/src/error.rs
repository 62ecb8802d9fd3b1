//! The one error type of the scheduling crate.

use thiserror::Error;

/// Everything that can be wrong with a scheduling instance, a schedule or a file.
#[derive(Debug, Error)]
pub enum ScheduleError {
    /// A line of a file is not an instance or a schedule of this format.
    #[error("line {line}: {message}")]
    Parse {
        /// 1-based line number.
        line: usize,
        /// What the JSON reader said.
        message: String,
    },
    /// A number of the instance is out of its range (named with the range).
    #[error("{what} is {value}, but it must be {expected}")]
    OutOfRange {
        /// The field, named as in the file (for example "task 3's duration").
        what: String,
        /// The value given.
        value: f64,
        /// The range it must lie in.
        expected: &'static str,
    },
    /// The instance is not well formed (counts that disagree, unknown names).
    #[error("{0}")]
    Invalid(String),
    /// No team of the instance's robots can ever staff this task.
    #[error("task {task} can never be staffed: {why}")]
    Unstaffable {
        /// The task.
        task: usize,
        /// What it needs that the robots lack.
        why: String,
    },
    /// A schedule does not fit its instance (an unknown task or robot, a task left out).
    #[error("the schedule {0}")]
    BadSchedule(String),
    /// The robots of a schedule wait for each other in a cycle: no task of the cycle can start.
    #[error("the schedule deadlocks: {}", describe_waits(.waiting))]
    Deadlock {
        /// (robot, task) for every robot left waiting at a task whose team never completes.
        waiting: Vec<(usize, usize)>,
    },
    /// A search or generator setting is out of range.
    #[error("{0}")]
    Setting(String),
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The operating system's error.
        source: std::io::Error,
    },
}

fn describe_waits(waiting: &[(usize, usize)]) -> String {
    let shown: Vec<String> = waiting
        .iter()
        .take(8)
        .map(|(r, t)| format!("robot {r} waits at task {t}"))
        .collect();
    let more = waiting.len().saturating_sub(shown.len());
    let tail = if more > 0 {
        format!(" and {more} more")
    } else {
        String::new()
    };
    format!("{}{tail}, whose teams never complete", shown.join(", "))
}

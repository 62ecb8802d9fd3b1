//! JSON formats (versioned), JSON Lines datasets and atomic file writes.
//!
//! An instance file is one JSON object:
//! `{"format": "afg-instance", "version": 1, "beta": 1.0, "robots": [{"x":..,"y":..}, ..],
//!   "tasks": [{"position": {..}, "reward": .., "eps": .., "capacity": ..}, ..],
//!   "generator": {..}}` (`capacity` and `generator` optional).
//! A dataset is a JSON Lines file with one such object per line.
//! An assignment file is `{"format": "afg-assignment", "version": 1, "tasks": [0, 3, null, ..]}`,
//! with three optional fields: `summary` (any JSON object: what the solver reports
//! beside it, ignored when read), and `left_robots` / `left_tasks` (robot and task
//! indices of this assignment that are gone, for a warm start on a changed instance:
//! [`PreviousAssignment`]).

use std::fs;
use std::io::Write;
use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::{Assignment, GameError, GeneratorConfig, Instance, Point, RobotId, Task, TaskId};

/// Format name of instance documents.
pub const INSTANCE_FORMAT: &str = "afg-instance";
/// Format name of assignment documents.
pub const ASSIGNMENT_FORMAT: &str = "afg-assignment";
/// Version of both formats written by this build.
pub const FORMAT_VERSION: u32 = 1;

/// The serialised shape of an [`Instance`]; deserialising validates it.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct InstanceFile {
    format: String,
    version: u32,
    beta: f64,
    robots: Vec<Point>,
    tasks: Vec<Task>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    generator: Option<GeneratorConfig>,
}

fn check_header(format: &str, version: u32, expected: &'static str) -> Result<(), GameError> {
    if format != expected {
        return Err(GameError::WrongFormat {
            expected,
            found: format.to_owned(),
        });
    }
    if version != FORMAT_VERSION {
        return Err(GameError::UnsupportedVersion {
            format: expected,
            found: version,
            supported: FORMAT_VERSION,
        });
    }
    Ok(())
}

impl TryFrom<InstanceFile> for Instance {
    type Error = GameError;
    fn try_from(f: InstanceFile) -> Result<Self, GameError> {
        check_header(&f.format, f.version, INSTANCE_FORMAT)?;
        let inst = Instance::new(f.robots, f.tasks, f.beta)?;
        Ok(match f.generator {
            Some(g) => inst.with_generator(g),
            None => inst,
        })
    }
}

impl From<Instance> for InstanceFile {
    fn from(inst: Instance) -> Self {
        InstanceFile {
            format: INSTANCE_FORMAT.to_owned(),
            version: FORMAT_VERSION,
            beta: inst.beta(),
            robots: inst.robots().to_vec(),
            tasks: inst.tasks().to_vec(),
            generator: inst.generator().cloned(),
        }
    }
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct AssignmentFile {
    format: String,
    version: u32,
    tasks: Vec<Option<TaskId>>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    left_robots: Vec<RobotId>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    left_tasks: Vec<TaskId>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    summary: Option<serde_json::Value>,
}

impl AssignmentFile {
    fn parse(text: &str, line: Option<usize>) -> Result<Self, GameError> {
        let file: AssignmentFile =
            serde_json::from_str(strip_bom(text)).map_err(json_error(line))?;
        check_header(&file.format, file.version, ASSIGNMENT_FORMAT)?;
        Ok(file)
    }
}

fn json_error(line: Option<usize>) -> impl FnOnce(serde_json::Error) -> GameError {
    move |source| GameError::Json { line, source }
}

/// Parses a JSON error, unwrapping a validation error raised inside serde.
fn parse_instance(text: &str, line: Option<usize>) -> Result<Instance, GameError> {
    // Deserialise the raw shape first so that validation errors keep their type.
    let file: InstanceFile = serde_json::from_str(strip_bom(text)).map_err(json_error(line))?;
    Instance::try_from(file)
}

impl Instance {
    /// Parses an instance document and validates it.
    ///
    /// # Errors
    /// [`GameError::Json`] for malformed JSON or a wrong shape,
    /// [`GameError::WrongFormat`] / [`GameError::UnsupportedVersion`] for another kind of
    /// document, and any validation error of [`Instance::new`].
    ///
    /// # Examples
    /// ```
    /// use afg_game::{GameError, GeneratorConfig, Instance};
    /// let inst = GeneratorConfig::paper(6, 2, 1).generate()?;
    /// assert_eq!(Instance::from_json(&inst.to_json())?, inst);
    /// let err = Instance::from_json(r#"{"format":"afg-instance","version":9}"#).unwrap_err();
    /// assert!(matches!(err, GameError::Json { .. }));
    /// # Ok::<(), GameError>(())
    /// ```
    pub fn from_json(text: &str) -> Result<Self, GameError> {
        parse_instance(text, None)
    }

    /// The instance as one line of compact JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).expect("an instance always serialises")
    }

    /// Reads an instance file.
    ///
    /// # Errors
    /// [`GameError::Io`] if the file cannot be read, otherwise as [`Instance::from_json`].
    pub fn read(path: &Path) -> Result<Self, GameError> {
        Self::from_json(&read_to_string(path)?)
    }

    /// Writes the instance to `path` atomically.
    ///
    /// # Errors
    /// [`GameError::Io`] if the file cannot be written.
    pub fn write(&self, path: &Path) -> Result<(), GameError> {
        write_atomic(path, self.to_json().as_bytes())
    }
}

impl Assignment {
    /// The assignment as a JSON document.
    ///
    /// # Examples
    /// ```
    /// use afg_game::{Assignment, GeneratorConfig, RobotId, TaskId};
    /// let inst = GeneratorConfig::paper(2, 2, 1).generate()?;
    /// let mut a = Assignment::unassigned(2, 2);
    /// a.set(RobotId(1), Some(TaskId(0)));
    /// assert_eq!(a.to_json(), r#"{"format":"afg-assignment","version":1,"tasks":[null,0]}"#);
    /// assert_eq!(Assignment::from_json(&a.to_json(), &inst)?, a);
    /// # Ok::<(), afg_game::GameError>(())
    /// ```
    pub fn to_json(&self) -> String {
        self.to_json_with_summary(None)
    }

    /// The assignment as a JSON document with a `summary` object beside it (what a
    /// solver reports: welfare, coalition sizes, stability; ignored when read back).
    ///
    /// # Examples
    /// ```
    /// use afg_game::{Assignment, GeneratorConfig};
    /// let inst = GeneratorConfig::paper(2, 2, 1).generate()?;
    /// let a = Assignment::unassigned(2, 2);
    /// let text = a.to_json_with_summary(Some(serde_json::json!({"welfare": 0.0})));
    /// assert!(text.ends_with(r#""summary":{"welfare":0.0}}"#));
    /// assert_eq!(Assignment::from_json(&text, &inst)?, a);
    /// # Ok::<(), afg_game::GameError>(())
    /// ```
    pub fn to_json_with_summary(&self, summary: Option<serde_json::Value>) -> String {
        let file = AssignmentFile {
            format: ASSIGNMENT_FORMAT.to_owned(),
            version: FORMAT_VERSION,
            tasks: self.tasks().to_vec(),
            left_robots: Vec::new(),
            left_tasks: Vec::new(),
            summary,
        };
        serde_json::to_string(&file).expect("an assignment always serialises")
    }

    /// Parses an assignment document and validates it against `instance`.
    ///
    /// # Errors
    /// [`GameError::Json`], [`GameError::WrongFormat`], [`GameError::UnsupportedVersion`],
    /// and the errors of [`Assignment::from_tasks`].
    pub fn from_json(text: &str, instance: &Instance) -> Result<Self, GameError> {
        let file = AssignmentFile::parse(text, None)?;
        if !file.left_robots.is_empty() || !file.left_tasks.is_empty() {
            return Err(GameError::Reallocation(
                "the file names robots or tasks that left: read it as a PreviousAssignment".into(),
            ));
        }
        Assignment::from_tasks(instance, file.tasks)
    }
}

/// An assignment of an earlier instance, with the robots and tasks that have left
/// since, to be carried over to the instance as it is now.
///
/// The new instance keeps the surviving robots in their old order, followed by any
/// robots that joined, and likewise the surviving tasks followed by new ones. Carried
/// over, survivors keep their task (with its new index); robots that joined, or whose
/// task left, are unassigned.
///
/// # Examples
/// ```
/// use afg_game::io::PreviousAssignment;
/// use afg_game::{GeneratorConfig, RobotId, TaskId};
/// // Three robots on tasks 1, 0, 1; robot 1 left and two robots joined.
/// let old = r#"{"format":"afg-assignment","version":1,"tasks":[1,0,1],"left_robots":[1]}"#;
/// let now = GeneratorConfig::paper(4, 2, 7).generate()?;
/// let start = PreviousAssignment::from_json(old)?.carry_over(&now)?;
/// assert_eq!(start.tasks(), &[Some(TaskId(1)), Some(TaskId(1)), None, None]);
/// # Ok::<(), afg_game::GameError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct PreviousAssignment {
    /// The old assignment, indexed by the old robot ids.
    pub tasks: Vec<Option<TaskId>>,
    /// Old robot ids that left.
    pub left_robots: Vec<RobotId>,
    /// Old task ids that left.
    pub left_tasks: Vec<TaskId>,
}

impl PreviousAssignment {
    /// Parses an assignment document (`left_robots` and `left_tasks` optional).
    ///
    /// # Errors
    /// [`GameError::Json`], [`GameError::WrongFormat`], [`GameError::UnsupportedVersion`].
    pub fn from_json(text: &str) -> Result<Self, GameError> {
        let file = AssignmentFile::parse(text, None)?;
        Ok(PreviousAssignment {
            tasks: file.tasks,
            left_robots: file.left_robots,
            left_tasks: file.left_tasks,
        })
    }

    /// Robots of the old assignment that are still there.
    pub fn survivors(&self) -> usize {
        self.tasks.len() - self.left_robots.len()
    }

    /// The starting assignment on `instance` (see the type's docs).
    ///
    /// # Errors
    /// [`GameError::Reallocation`] if a task index is beyond the tasks the old
    /// instance can have had, a left robot is out of range, a robot or task is named
    /// twice, or the instance has fewer robots or tasks than survived; the errors of
    /// [`Assignment::from_tasks`] if the survivors overfill a task.
    pub fn carry_over(&self, instance: &Instance) -> Result<Assignment, GameError> {
        let bad = |what: String| Err(GameError::Reallocation(what));
        // The old instance had the surviving tasks (at most the new M) and the left ones.
        let most_tasks = instance.num_tasks() + self.left_tasks.len();
        let old_tasks = self
            .tasks
            .iter()
            .flatten()
            .chain(&self.left_tasks)
            .map(|j| j.index() + 1)
            .max()
            .unwrap_or(0);
        if old_tasks > most_tasks {
            return bad(format!(
                "task {} is out of range: the instance has {} tasks and {} left, so the \
                 old one had at most {most_tasks}",
                old_tasks - 1,
                instance.num_tasks(),
                self.left_tasks.len()
            ));
        }
        let mut robot_gone = vec![false; self.tasks.len()];
        for &r in &self.left_robots {
            match robot_gone.get_mut(r.index()) {
                Some(g) if !*g => *g = true,
                Some(_) => return bad(format!("robot {r} is named twice in left_robots")),
                None => {
                    return bad(format!(
                        "left robot {r} is out of range (the assignment has {} robots)",
                        self.tasks.len()
                    ));
                }
            }
        }
        // New index of each old task, None if it left.
        let mut task_map: Vec<Option<u32>> = vec![Some(0); old_tasks];
        for &j in &self.left_tasks {
            if task_map[j.index()].is_none() {
                return bad(format!("task {j} is named twice in left_tasks"));
            }
            task_map[j.index()] = None;
        }
        let mut next = 0;
        for slot in task_map.iter_mut().flatten() {
            *slot = next;
            next += 1;
        }
        if (next as usize) > instance.num_tasks() || self.survivors() > instance.num_robots() {
            return bad(format!(
                "{} robots and {next} tasks survived, but the instance has only {} and {}",
                self.survivors(),
                instance.num_robots(),
                instance.num_tasks()
            ));
        }
        let mut tasks: Vec<Option<TaskId>> = self
            .tasks
            .iter()
            .zip(&robot_gone)
            .filter(|(_, gone)| !**gone)
            .map(|(t, _)| t.and_then(|j| task_map[j.index()]).map(TaskId))
            .collect();
        tasks.resize(instance.num_robots(), None);
        Assignment::from_tasks(instance, tasks)
    }
}

/// Parses one instance document, or a JSON Lines text of several (a dataset).
///
/// # Errors
/// The error of [`Instance::from_json`] if the text is one JSON document, otherwise
/// that of [`parse_dataset`] (which names the line).
///
/// # Examples
/// ```
/// use afg_game::{GeneratorConfig, io};
/// let a = GeneratorConfig::paper(5, 2, 1).generate()?;
/// let b = GeneratorConfig::paper(7, 2, 2).generate()?;
/// assert_eq!(io::parse_instances(&a.to_json())?, vec![a.clone()]);
/// let lines = io::dataset_to_jsonl(&[a.clone(), b.clone()]);
/// assert_eq!(io::parse_instances(&lines)?, vec![a, b]);
/// # Ok::<(), afg_game::GameError>(())
/// ```
pub fn parse_instances(text: &str) -> Result<Vec<Instance>, GameError> {
    let text = strip_bom(text);
    if serde_json::from_str::<serde::de::IgnoredAny>(text).is_ok() {
        return Ok(vec![Instance::from_json(text)?]);
    }
    parse_dataset(text)
}

/// Reads a JSON Lines dataset: one instance per non-empty line.
///
/// # Errors
/// [`GameError::Io`] if the file cannot be read; a parse or validation error
/// names its line in [`GameError::Json`].
pub fn read_dataset(path: &Path) -> Result<Vec<Instance>, GameError> {
    parse_dataset(&read_to_string(path)?)
}

/// Parses the text of a JSON Lines dataset; lines may end in CRLF, and a leading
/// byte order mark is skipped.
///
/// # Errors
/// As [`read_dataset`].
pub fn parse_dataset(text: &str) -> Result<Vec<Instance>, GameError> {
    strip_bom(text)
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| {
            parse_instance(l, Some(i + 1)).map_err(|e| match e {
                GameError::Json { .. } => e,
                other => GameError::AtLine {
                    line: i + 1,
                    source: Box::new(other),
                },
            })
        })
        .collect()
}

/// The JSON Lines text of a dataset.
pub fn dataset_to_jsonl(instances: &[Instance]) -> String {
    let mut out = String::new();
    for inst in instances {
        out.push_str(&inst.to_json());
        out.push('\n');
    }
    out
}

/// Writes `bytes` to `path` atomically and durably: to a new temporary file beside it
/// (an unpredictable name, opened with `create_new`, so no existing file or symlink is
/// followed), flushed and synced, renamed over the target, and the directory synced,
/// so that neither a crash nor a full disk ever leaves a truncated file in its place.
///
/// # Errors
/// [`GameError::Io`] if any step fails; the target is then untouched.
///
/// # Examples
/// ```
/// let path = std::env::temp_dir().join(format!("afg-doc-atomic-{}", std::process::id()));
/// afg_game::io::write_atomic(&path, b"one")?;
/// afg_game::io::write_atomic(&path, b"two")?;
/// assert_eq!(std::fs::read(&path)?, b"two");
/// # std::fs::remove_file(&path)?;
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), GameError> {
    write_atomic_with(path, |f| f.write_all(bytes))
}

/// [`write_atomic`] with the contents written by `write` into the temporary file (for
/// writers that stream, such as a model recorder).
///
/// # Errors
/// As [`write_atomic`], and `write`'s error.
pub fn write_atomic_with(
    path: &Path,
    write: impl FnOnce(&mut fs::File) -> std::io::Result<()>,
) -> Result<(), GameError> {
    use std::hash::{BuildHasher, Hasher};
    let io_err = |source| GameError::Io {
        path: path.display().to_string(),
        source,
    };
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .ok_or_else(|| io_err(std::io::Error::other("not a file path")))?;
    let (tmp, mut file) = loop {
        // A fresh random key per try (std's hasher seeds are random per process).
        let key = std::collections::hash_map::RandomState::new()
            .build_hasher()
            .finish();
        let tmp = dir.join(format!(".{}.{key:016x}.tmp", name.to_string_lossy()));
        match fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)
        {
            Ok(f) => break (tmp, f),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(io_err(e)),
        }
    };
    let result = (|| {
        write(&mut file)?;
        file.flush()?;
        file.sync_all()?;
        drop(file);
        fs::rename(&tmp, path)?;
        sync_dir(dir)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result.map_err(io_err)
}

/// Syncs a directory, so that a rename in it survives a crash (a no-op where
/// directories cannot be opened, as on Windows).
pub fn sync_dir(dir: &Path) -> std::io::Result<()> {
    #[cfg(unix)]
    fs::File::open(dir)?.sync_all()?;
    #[cfg(not(unix))]
    let _ = dir;
    Ok(())
}

fn read_to_string(path: &Path) -> Result<String, GameError> {
    fs::read_to_string(path).map_err(|source| GameError::Io {
        path: path.display().to_string(),
        source,
    })
}

/// `text` without a leading UTF-8 byte order mark (which some editors write).
pub fn strip_bom(text: &str) -> &str {
    text.strip_prefix('\u{feff}').unwrap_or(text)
}

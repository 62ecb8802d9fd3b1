//! JSON formats (versioned) and JSON Lines datasets (files are written through
//! [`crate::fs`]).
//!
//! An instance file is one JSON object:
//! `{"format": "afg-instance", "version": 1, "beta": 1.0, "robots": [{"x":..,"y":..}, ..],
//!   "tasks": [{"position": {..}, "reward": .., "eps": .., "capacity": ..}, ..],
//!   "allow_void": true, "generator": {..}}` (`capacity`, `allow_void` and `generator`
//!   optional; `allow_void`, absent in the paper's game, lets robots join the void task
//!   of GRAPE's game). The team games add three optional fields, written only when used:
//!   a task's `min_team` (its threshold, default 1) and `requires` (S amounts of skills),
//!   and a robot's `skills` (S amounts), e.g. `{"x": 0.1, "y": 0.5, "skills": [1, 0]}`.
//! A dataset is a JSON Lines file with one such object per line.
//! An assignment file is `{"format": "afg-assignment", "version": 1, "tasks": [0, 3, -1, ..]}`
//! (−1: no task; files of older versions of afg wrote `null`, which reads the same),
//! with three optional fields: `summary` (any JSON object: what the solver reports
//! beside it, ignored when read), and `left_robots` / `left_tasks` (robot and task
//! indices of this assignment that are gone, for a warm start on a changed instance:
//! [`PreviousAssignment`](crate::realloc::PreviousAssignment)).

use std::fs;
use std::path::Path;

use serde::{Deserialize, Serialize};

mod instance_file;
pub(crate) use instance_file::InstanceFile;

use crate::{Assignment, GameError, Instance, RobotId, TaskId};

/// Format name of instance documents.
pub const INSTANCE_FORMAT: &str = "afg-instance";
/// Format name of assignment documents.
pub const ASSIGNMENT_FORMAT: &str = "afg-assignment";
/// Version of both formats written by this build.
pub const FORMAT_VERSION: u32 = 1;

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

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct AssignmentFile {
    format: String,
    version: u32,
    /// Each robot's task; −1 (or `null`) for none: the void task in GRAPE's game, a
    /// robot yet to act in a partial assignment.
    #[serde(with = "minus_one_for_none")]
    pub(crate) tasks: Vec<Option<TaskId>>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub(crate) left_robots: Vec<RobotId>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub(crate) left_tasks: Vec<TaskId>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    summary: Option<serde_json::Value>,
}

impl AssignmentFile {
    pub(crate) fn parse(text: &str, line: Option<usize>) -> Result<Self, GameError> {
        let file: AssignmentFile =
            serde_json::from_str(strip_bom(text)).map_err(json_error(line))?;
        check_header(&file.format, file.version, ASSIGNMENT_FORMAT)?;
        Ok(file)
    }
}

/// Task lists as files write them: a task index, or −1 for none (`null`, which older
/// files wrote, reads the same).
mod minus_one_for_none {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    use crate::TaskId;

    pub(super) fn serialize<S: Serializer>(
        tasks: &[Option<TaskId>],
        serializer: S,
    ) -> Result<S::Ok, S::Error> {
        let indices: Vec<i64> = tasks
            .iter()
            .map(|t| t.map_or(-1, |t| i64::from(t.0)))
            .collect();
        indices.serialize(serializer)
    }

    pub(super) fn deserialize<'de, D: Deserializer<'de>>(
        deserializer: D,
    ) -> Result<Vec<Option<TaskId>>, D::Error> {
        let indices = Vec::<Option<i64>>::deserialize(deserializer)?;
        indices
            .into_iter()
            .enumerate()
            .map(|(robot, t)| match t {
                None | Some(-1) => Ok(None),
                Some(t) => u32::try_from(t).map(|t| Some(TaskId(t))).map_err(|_| {
                    serde::de::Error::custom(format!(
                        "robot {robot} has task {t}: a task is an index 0..M, or -1 for none"
                    ))
                }),
            })
            .collect()
    }
}

/// Where a JSON document failed on a non-number (`NaN`, `Infinity`, `-Infinity`, as
/// Python's `json` writes them): the message naming the token, its place and its field,
/// or `None` for any other error.
///
/// # Examples
/// ```
/// let text = r#"{"tasks":[{"workload":NaN}]}"#;
/// let err = serde_json::from_str::<serde_json::Value>(text).unwrap_err();
/// let message = afg_game::io::non_finite_number(text, &err).expect("a NaN");
/// assert!(message.contains("`NaN`") && message.contains("field `workload`"), "{message}");
/// assert!(message.contains("JSON has no NaN or Infinity"));
/// let err = serde_json::from_str::<serde_json::Value>("{,}").unwrap_err();
/// assert!(afg_game::io::non_finite_number("{,}", &err).is_none());
/// ```
pub fn non_finite_number(text: &str, err: &serde_json::Error) -> Option<String> {
    if !err.is_syntax() {
        return None;
    }
    let line_start: usize = text
        .split_inclusive('\n')
        .take(err.line().saturating_sub(1))
        .map(str::len)
        .sum();
    let line = &text[line_start..];
    // serde_json's column is at or just after the token's first character.
    let from = line
        .char_indices()
        .nth(err.column().saturating_sub(2))
        .map_or(line.len(), |(i, _)| i);
    let window = &line[from..];
    let start = ["-Infinity", "Infinity", "NaN"]
        .iter()
        .filter_map(|token| window.find(token).filter(|&i| i <= 2).map(|i| (i, *token)))
        .min()?;
    let before = &text[..line_start + from + start.0];
    let field = before
        .rfind(':')
        .and_then(|colon| before[..colon].trim_end().strip_suffix('"'))
        .and_then(|key| key.rfind('"').map(|open| &key[open + 1..]));
    let field = field.map_or(String::new(), |f| format!(" (field `{f}`)"));
    Some(format!(
        "`{}` at line {} column {}{field}: JSON has no NaN or Infinity; write a finite number",
        start.1,
        err.line(),
        err.column()
    ))
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
        crate::fs::write_atomic(path, self.to_json().as_bytes())
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
    /// assert_eq!(a.to_json(), r#"{"format":"afg-assignment","version":1,"tasks":[-1,0]}"#);
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

/// Reads a file of instances as [`parse_instances`] does (one instance document, or
/// JSON Lines); the path `-` reads standard input. Every front end reads `--input` and
/// Python's `read_jsonl` through this.
///
/// # Errors
/// [`GameError::Io`] if the file cannot be read, [`GameError::InFile`] naming the file
/// around a parse or validation error, and [`GameError::NoInstances`] for a file with
/// none.
///
/// # Examples
/// ```
/// use afg_game::{GameError, GeneratorConfig, io};
/// let dir = std::env::temp_dir().join(format!("afg-doc-read-{}", std::process::id()));
/// std::fs::create_dir_all(&dir)?;
/// let inst = GeneratorConfig::paper(5, 2, 1).generate()?;
/// std::fs::write(dir.join("one.json"), inst.to_json())?;
/// assert_eq!(io::read_instances(&dir.join("one.json"))?, vec![inst]);
/// std::fs::write(dir.join("empty.jsonl"), "\n")?;
/// let err = io::read_instances(&dir.join("empty.jsonl")).unwrap_err();
/// assert!(matches!(err, GameError::NoInstances { .. }));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn read_instances(path: &Path) -> Result<Vec<Instance>, GameError> {
    let name = path.display().to_string();
    let text = if path.as_os_str() == "-" {
        std::io::read_to_string(std::io::stdin()).map_err(|source| GameError::Io {
            path: "standard input".into(),
            source,
        })?
    } else {
        read_to_string(path)?
    };
    let instances = parse_instances(&text).map_err(|source| GameError::InFile {
        path: name.clone(),
        source: Box::new(source),
    })?;
    if instances.is_empty() {
        return Err(GameError::NoInstances { path: name });
    }
    Ok(instances)
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

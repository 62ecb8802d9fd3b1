//! afg for Python: a thin layer over the crates. Every number comes from them; this
//! crate only converts types at the border (numpy arrays in and out, the crates' errors
//! to Python exceptions) and releases the GIL around long calls.

// PyO3's macros expand to unsafe code; nothing written here is unsafe.
#![allow(unsafe_code)]

use std::path::PathBuf;
use std::sync::Arc;

use afg_game::{Assignment, Instance, Named, Point, Preference, Task, TaskId};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyType;

mod args;
mod dataset;
mod env;
mod interrupt;
mod mission;
mod mission_env;
mod schedule;
mod solve;

/// One of afg's own exceptions (`afg/_errors.py`: `AfgError` and its subclasses),
/// carrying `message`.
fn afg_error(class: &str, message: String) -> PyErr {
    Python::attach(|py| {
        let class = py
            .import("afg._errors")
            .and_then(|module| module.getattr(class))
            .and_then(|class| Ok(class.cast_into::<PyType>()?));
        match class {
            Ok(class) => PyErr::from_type(class, message),
            Err(e) => e,
        }
    })
}

/// Raises `message` (where there is one) as a Python `UserWarning` pointing at the
/// caller's line.
pub(crate) fn warn(py: Python<'_>, message: Option<String>) -> PyResult<()> {
    let Some(message) = message else {
        return Ok(());
    };
    let message = std::ffi::CString::new(message).map_err(bad_input)?;
    PyErr::warn(
        py,
        &py.get_type::<pyo3::exceptions::PyUserWarning>(),
        &message,
        1,
    )
}

/// Bad input as `afg.InvalidInputError` (also a `ValueError`) with the same message.
pub(crate) fn bad_input(e: impl std::fmt::Display) -> PyErr {
    afg_error("InvalidInputError", e.to_string())
}

/// A missing file as `afg.MissingFileError` (also a `FileNotFoundError`).
pub(crate) fn missing_file(e: impl std::fmt::Display) -> PyErr {
    afg_error("MissingFileError", e.to_string())
}

/// A request refused in the object's state as `afg.RefusedError` (also a
/// `RuntimeError`).
pub(crate) fn refused(e: impl std::fmt::Display) -> PyErr {
    afg_error("RefusedError", e.to_string())
}

/// Whether `e` is, at its root, a file that is not there.
fn not_found(e: &(dyn std::error::Error + 'static)) -> bool {
    let mut cause = Some(e);
    while let Some(e) = cause {
        if let Some(io) = e.downcast_ref::<std::io::Error>() {
            return io.kind() == std::io::ErrorKind::NotFound;
        }
        cause = e.source();
    }
    false
}

/// An error of the crates: `afg.MissingFileError` where a file is missing,
/// `afg.InvalidInputError` otherwise.
pub(crate) fn crate_error(e: impl std::error::Error + 'static) -> PyErr {
    if not_found(&e) {
        missing_file(e)
    } else {
        bad_input(e)
    }
}

/// An integer vector from Python: a numpy int64 array (read in place) or any sequence.
#[derive(FromPyObject)]
pub(crate) enum IntVector<'py> {
    Array(PyReadonlyArray1<'py, i64>),
    List(Vec<i64>),
}

impl IntVector<'_> {
    pub(crate) fn to_vec(&self) -> Vec<i64> {
        match self {
            IntVector::Array(a) => a.as_array().to_vec(),
            IntVector::List(v) => v.clone(),
        }
    }
}

/// What `__reduce__` returns for an object that pickles as a JSON document: the
/// class's `method` (a static method taking the document) and the document.
pub(crate) fn reduce_to<'py, T: pyo3::PyTypeInfo>(
    py: Python<'py>,
    method: &str,
    document: String,
) -> PyResult<(Bound<'py, PyAny>, (String,))> {
    Ok((py.get_type::<T>().getattr(method)?, (document,)))
}

/// The value a user named (`"balanced"`, `"bounded"`, …), or a `ValueError` listing the
/// names there are.
pub(crate) fn named<T: Named>(name: &str) -> PyResult<T> {
    T::from_name(name).map_err(bad_input)
}

/// One game: N robots, M tasks, the distance penalty beta (validated on construction).
#[pyclass(name = "Instance", module = "afg", frozen)]
#[derive(Clone)]
pub struct PyInstance {
    pub(crate) inner: Arc<Instance>,
}

impl PyInstance {
    pub(crate) fn new_from(inner: Instance) -> Self {
        PyInstance {
            inner: Arc::new(inner),
        }
    }

    /// `tasks` (robot i's task, -1 for none) as an assignment of this instance.
    pub(crate) fn assignment(&self, tasks: &IntVector<'_>) -> PyResult<Assignment> {
        Assignment::from_tasks(&self.inner, task_ids(tasks)?).map_err(crate_error)
    }
}

/// Robot i's task of each entry (-1 for none), as task ids.
pub(crate) fn task_ids(tasks: &IntVector<'_>) -> PyResult<Vec<Option<TaskId>>> {
    tasks
        .to_vec()
        .into_iter()
        .enumerate()
        .map(|(i, t)| match t {
            -1 => Ok(None),
            t => u32::try_from(t).map(|t| Some(TaskId(t))).map_err(|_| {
                bad_input(format!(
                    "robot {i} has task {t}: a task is 0..M-1, or -1 for none"
                ))
            }),
        })
        .collect()
}

/// Robot i's task of `assignment` at entry i, -1 for none.
pub(crate) fn task_indices(assignment: &Assignment) -> Vec<i64> {
    assignment
        .tasks()
        .iter()
        .map(|t| t.map_or(-1, |j| i64::from(j.0)))
        .collect()
}

fn points(array: &PyReadonlyArray2<'_, f64>, what: &str) -> PyResult<Vec<Point>> {
    let a = array.as_array();
    if a.ncols() != 2 {
        return Err(bad_input(format!(
            "{what} must have shape (K, 2), got {:?}",
            a.shape()
        )));
    }
    Ok(a.rows()
        .into_iter()
        .map(|r| Point::new(r[0], r[1]))
        .collect())
}

fn point_array<'py>(
    py: Python<'py>,
    points: impl Iterator<Item = Point>,
) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = points.flat_map(|p| [p.x, p.y]).collect();
    Array2::from_shape_vec((flat.len() / 2, 2), flat)
        .expect("two coordinates per point")
        .into_pyarray(py)
}

#[pymethods]
impl PyInstance {
    /// Builds and validates an instance from arrays: robot positions (N, 2), task
    /// positions (M, 2), rewards (M,), eps (M,), optional capacities (M,; -1 = none).
    #[new]
    #[pyo3(signature = (robots, tasks, rewards, eps, capacities=None, beta=1.0, allow_void=false, min_team=None, skills=None, requires=None))]
    // Python's keyword arguments, one per field.
    #[allow(clippy::too_many_arguments)]
    fn py_new(
        robots: PyReadonlyArray2<'_, f64>,
        tasks: PyReadonlyArray2<'_, f64>,
        rewards: Vec<f64>,
        eps: Vec<f64>,
        capacities: Option<IntVector<'_>>,
        beta: f64,
        allow_void: bool,
        min_team: Option<args::Integers>,
        skills: Option<args::IntegerRows>,
        requires: Option<args::IntegerRows>,
    ) -> PyResult<Self> {
        let (min_team, skills, requires) = (
            min_team.map(|v| v.0),
            skills.map(|r| r.0),
            requires.map(|r| r.0),
        );
        let positions = points(&tasks, "tasks")?;
        let m = positions.len();
        let capacities = capacities
            .map(|c| c.to_vec())
            .unwrap_or_else(|| vec![-1; m]);
        if rewards.len() != m || eps.len() != m || capacities.len() != m {
            return Err(bad_input(format!(
                "{m} task positions but {} rewards, {} eps and {} capacities",
                rewards.len(),
                eps.len(),
                capacities.len()
            )));
        }
        let tasks = (0..m)
            .map(|j| {
                let capacity = match capacities[j] {
                    -1 => Ok(None),
                    c => usize::try_from(c)
                        .map(Some)
                        .map_err(|_| bad_input(format!("task {j} has capacity {c}; -1 for none"))),
                }?;
                Ok(Task {
                    position: positions[j],
                    reward: rewards[j],
                    eps: eps[j],
                    capacity,
                })
            })
            .collect::<PyResult<Vec<_>>>()?;
        let robots = points(&robots, "robots")?;
        let inst = if allow_void {
            Instance::with_void(robots, tasks, beta)
        } else {
            Instance::new(robots, tasks, beta)
        }
        .map_err(crate_error)?;
        if min_team.is_none() && skills.is_none() && requires.is_none() {
            return Ok(Self::new_from(inst));
        }
        let whole = |what: &str, v: i64| {
            u32::try_from(v).map_err(|_| {
                bad_input(format!(
                    "{what} holds {v}: thresholds and skill amounts are whole numbers from 0 to {}",
                    u32::MAX
                ))
            })
        };
        let matrix = |what: &str, rows: Option<Vec<Vec<i64>>>| -> PyResult<Vec<Vec<u32>>> {
            rows.unwrap_or_default()
                .into_iter()
                .map(|row| row.into_iter().map(|v| whole(what, v)).collect())
                .collect()
        };
        let min_team = min_team
            .unwrap_or_default()
            .into_iter()
            .map(|k| whole("min_team", k).map(|k| k as usize))
            .collect::<PyResult<Vec<usize>>>()?;
        let (skills, requires) = (matrix("skills", skills)?, matrix("requires", requires)?);
        let inst = inst
            .with_teams(min_team, &skills, &requires)
            .map_err(crate_error)?;
        Ok(Self::new_from(inst))
    }

    /// Reads an instance file (format "afg-instance").
    #[staticmethod]
    fn from_json(path: PathBuf) -> PyResult<Self> {
        Instance::read(&path)
            .map(Self::new_from)
            .map_err(crate_error)
    }

    /// Parses an instance document from a string.
    #[staticmethod]
    fn parse(text: &str) -> PyResult<Self> {
        Instance::from_json(text)
            .map(Self::new_from)
            .map_err(crate_error)
    }

    /// An instance from the dict of an "afg-instance" document (as `json.load` gives).
    #[staticmethod]
    fn from_dict(py: Python<'_>, document: &Bound<'_, PyAny>) -> PyResult<Self> {
        let text: String = py
            .import("json")?
            .call_method1("dumps", (document,))?
            .extract()?;
        Self::parse(&text)
    }

    /// The "afg-instance" document as a dict.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        py.import("json")?
            .call_method1("loads", (self.inner.to_json(),))
    }

    /// The instance as one line of JSON (format "afg-instance").
    fn to_json(&self) -> String {
        self.inner.to_json()
    }

    /// Writes the instance to `path` (atomically).
    fn write(&self, path: PathBuf) -> PyResult<()> {
        self.inner.write(&path).map_err(crate_error)
    }

    /// Number of robots N.
    #[getter]
    fn num_robots(&self) -> usize {
        self.inner.num_robots()
    }

    /// Number of tasks M.
    #[getter]
    fn num_tasks(&self) -> usize {
        self.inner.num_tasks()
    }

    /// Robot positions, shape (N, 2).
    #[getter]
    fn robots<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        point_array(py, self.inner.robots().iter().copied())
    }

    /// Task positions, shape (M, 2).
    #[getter]
    fn tasks<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        point_array(py, self.inner.tasks().iter().map(|t| t.position))
    }

    /// Initial rewards r_j, shape (M,).
    #[getter]
    fn rewards<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let v: Vec<f64> = self.inner.tasks().iter().map(|t| t.reward).collect();
        v.into_pyarray(py)
    }

    /// Bases eps_j, shape (M,).
    #[getter]
    fn eps<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let v: Vec<f64> = self.inner.tasks().iter().map(|t| t.eps).collect();
        v.into_pyarray(py)
    }

    /// Capacities, shape (M,), -1 where a task is unbounded.
    #[getter]
    fn capacities<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        let v: Vec<i64> = self
            .inner
            .tasks()
            .iter()
            .map(|t| {
                t.capacity
                    .map_or(-1, |c| i64::try_from(c).unwrap_or(i64::MAX))
            })
            .collect();
        v.into_pyarray(py)
    }

    /// Team thresholds `min_team`, shape (M,): a task earns nothing below it (1: the
    /// paper's game).
    #[getter]
    fn min_team<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        let v: Vec<i64> = (self.inner.task_ids())
            .map(|j| self.inner.min_team(j) as i64)
            .collect();
        v.into_pyarray(py)
    }

    /// Each robot's amount of each skill, shape (N, S) (S = 0 without skills).
    #[getter]
    fn skills<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<i64>> {
        let rows = self.inner.robot_ids().map(|i| self.inner.skills(i));
        skill_matrix(py, rows, self.inner.num_robots(), self.inner.num_skills())
    }

    /// What each task requires of each skill, shape (M, S).
    #[getter]
    fn requires<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<i64>> {
        let rows = self.inner.task_ids().map(|j| self.inner.requires(j));
        skill_matrix(py, rows, self.inner.num_tasks(), self.inner.num_skills())
    }

    /// The distance penalty beta.
    #[getter]
    fn beta(&self) -> f64 {
        self.inner.beta()
    }

    /// Whether a robot may join the void task (GRAPE's game; -1 in `tasks` vectors is
    /// then a robot in no coalition, utility 0). False for the paper's game.
    #[getter]
    fn allow_void(&self) -> bool {
        self.inner.allows_void()
    }

    /// Welfare of an assignment (`tasks[i]` = robot i's task, -1 for none).
    fn welfare(&self, tasks: IntVector<'_>) -> PyResult<f64> {
        Ok(self.inner.welfare(&self.assignment(&tasks)?))
    }

    /// Whether no robot strictly prefers another task ("balanced" or "selfish").
    #[pyo3(signature = (tasks, preference="balanced"))]
    fn is_stable(&self, tasks: IntVector<'_>, preference: &str) -> PyResult<bool> {
        let pref = crate::named::<Preference>(preference)?;
        Ok(self.inner.is_stable(&self.assignment(&tasks)?, pref))
    }

    /// Share of robots (0..=1) that prefer no other task.
    #[pyo3(signature = (tasks, preference="balanced"))]
    fn ns_rate(&self, tasks: IntVector<'_>, preference: &str) -> PyResult<f64> {
        let pref = crate::named::<Preference>(preference)?;
        Ok(self.inner.ns_rate(&self.assignment(&tasks)?, pref))
    }

    /// Pickles through the instance's JSON document.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, (String,))> {
        reduce_to::<PyInstance>(py, "parse", self.inner.to_json())
    }

    fn __eq__(&self, other: &Self) -> bool {
        self.inner == other.inner
    }

    fn __repr__(&self) -> String {
        let inst = &self.inner;
        let mut text = format!(
            "Instance(robots={}, tasks={}, beta={:?}",
            inst.num_robots(),
            inst.num_tasks(),
            inst.beta()
        );
        let thresholds: Vec<usize> = inst.task_ids().map(|j| inst.min_team(j)).collect();
        if thresholds.iter().any(|&k| k > 1) {
            let (lo, hi) = (thresholds.iter().min(), thresholds.iter().max());
            text += &format!(", min_team={}..{}", lo.unwrap_or(&1), hi.unwrap_or(&1));
        }
        if inst.num_skills() > 0 {
            text += &format!(", skills={}", inst.num_skills());
        }
        if inst.allows_void() {
            text += ", allow_void=True";
        }
        text + ")"
    }
}

/// A (rows, S) int64 array of skill amounts.
pub(crate) fn skill_matrix<'py, 'a>(
    py: Python<'py>,
    rows: impl Iterator<Item = &'a [u32]>,
    n: usize,
    s: usize,
) -> Bound<'py, PyArray2<i64>> {
    let flat: Vec<i64> = rows.flatten().map(|&q| i64::from(q)).collect();
    numpy::ndarray::Array2::from_shape_vec((n, s), flat)
        .expect("one row of S amounts each")
        .into_pyarray(py)
}

/// The compiled core of the `afg` package.
#[pymodule]
fn _afg(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyInstance>()?;
    dataset::register(m)?;
    solve::register(m)?;
    env::register(m)?;
    mission::register(m)?;
    mission_env::register(m)?;
    schedule::register(m)?;
    Ok(())
}

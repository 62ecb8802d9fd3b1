//! Schedules for Python: `afg.ScheduleInstance` (read, drawn, written),
//! `afg.schedule` (plan one, with its certified bound) and `afg.score_schedule` (play
//! anyone's), routes in and out as numpy arrays.

use std::path::PathBuf;
use std::sync::Arc;

use afg_schedule::{
    Evaluation, Family, Generate, Schedule, ScheduleError, ScheduleInstance, SolveOptions,
    read_instances,
};
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::bad_input;

/// A scheduling error as afg's exception: a missing file as `MissingFileError`, the rest
/// as `InvalidInputError`.
fn schedule_error(e: ScheduleError) -> PyErr {
    match e {
        ScheduleError::Io { ref source, .. } if source.kind() == std::io::ErrorKind::NotFound => {
            crate::missing_file(e)
        }
        other => bad_input(other),
    }
}

/// A scheduling instance: depots, robots, tasks that need teams (`min_team` or skills),
/// speed and `max_wait` (validated). DCMRTA's test set is `datasets/dcmrta-20a50t/`.
#[pyclass(name = "ScheduleInstance", module = "afg", frozen)]
pub(crate) struct PyScheduleInstance {
    inner: Arc<ScheduleInstance>,
}

#[pymethods]
impl PyScheduleInstance {
    /// Reads every instance of a JSON Lines file (DCMRTA's layout).
    #[staticmethod]
    fn read(path: PathBuf) -> PyResult<Vec<Self>> {
        let all = read_instances(&path).map_err(schedule_error)?;
        Ok(all
            .into_iter()
            .map(|i| PyScheduleInstance { inner: Arc::new(i) })
            .collect())
    }

    /// Parses one instance from a JSON string.
    #[staticmethod]
    fn parse(text: &str) -> PyResult<Self> {
        Ok(PyScheduleInstance {
            inner: Arc::new(ScheduleInstance::from_json(text).map_err(schedule_error)?),
        })
    }

    /// Draws an instance: `family` "dcmrta" (robots at one depot, tasks needing 1–5
    /// robots) or "heteromrta" (5 species with a skill and a depot each, tasks requiring
    /// 1–5 skills); seeded.
    #[staticmethod]
    #[pyo3(signature = (family="dcmrta", robots=20, tasks=50, seed=0))]
    fn generate(family: &str, robots: usize, tasks: usize, seed: u64) -> PyResult<Self> {
        let family = Family::from_name(family).map_err(schedule_error)?;
        let inst = Generate {
            family,
            robots,
            tasks,
            seed,
        }
        .instance()
        .map_err(schedule_error)?;
        Ok(PyScheduleInstance {
            inner: Arc::new(inst),
        })
    }

    /// The instance as one line of JSON (the layout `read` and `afg schedule` read).
    fn to_json(&self) -> String {
        self.inner.to_json()
    }

    /// Number of robots.
    #[getter]
    fn num_robots(&self) -> usize {
        self.inner.num_robots()
    }

    /// Number of tasks.
    #[getter]
    fn num_tasks(&self) -> usize {
        self.inner.num_tasks()
    }

    /// The longest a robot may wait for its team.
    #[getter]
    fn max_wait(&self) -> f64 {
        self.inner.max_wait
    }

    /// Task positions, an (M, 2) float64 array.
    #[getter]
    fn task_positions<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let flat: Vec<f64> = self.inner.tasks.iter().flat_map(|t| [t.x, t.y]).collect();
        numpy::ndarray::Array2::from_shape_vec((self.inner.num_tasks(), 2), flat)
            .expect("two per task")
            .into_pyarray(py)
    }

    /// Task durations, an (M,) float64 array.
    #[getter]
    fn durations<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.inner
            .tasks
            .iter()
            .map(|t| t.duration)
            .collect::<Vec<_>>()
            .into_pyarray(py)
    }

    /// The certified lower bound on the makespan of every schedule of this instance.
    fn lower_bound(&self) -> f64 {
        self.inner.lower_bound().makespan
    }

    fn __repr__(&self) -> String {
        let needs = if self.inner.num_skills() > 0 {
            format!(", skills={}", self.inner.num_skills())
        } else {
            String::new()
        };
        format!(
            "afg.ScheduleInstance(robots={}, tasks={}, depots={}{needs}, speed={}, max_wait={})",
            self.inner.num_robots(),
            self.inner.num_tasks(),
            self.inner.depots.len(),
            self.inner.speed,
            self.inner.max_wait
        )
    }
}

/// Routes from Python: one sequence of task ids (a list or a numpy array) per robot.
fn routes_from(routes: &Bound<'_, PyAny>) -> PyResult<Schedule> {
    let mut out = Vec::new();
    for (i, route) in routes
        .try_iter()
        .map_err(|_| bad_input("routes must be one sequence of task ids per robot"))?
        .enumerate()
    {
        let route = route?;
        let ids: Vec<i64> = route
            .extract()
            .or_else(|_| route.call_method0("tolist").and_then(|l| l.extract()))
            .map_err(|_| {
                bad_input(format!(
                    "robot {i}'s route must be a sequence of whole task ids"
                ))
            })?;
        let ids = ids
            .into_iter()
            .map(|j| {
                usize::try_from(j).map_err(|_| {
                    bad_input(format!(
                        "robot {i}'s route names task {j}: task ids start at 0"
                    ))
                })
            })
            .collect::<PyResult<Vec<usize>>>()?;
        out.push(ids);
    }
    Ok(Schedule { routes: out })
}

/// A played schedule as a dict: numbers, per-task start and finish (numpy), where the
/// robots' time goes (`time_use`: working, driving, waiting, idle, means per robot that
/// add up to the makespan), the waits beyond `max_wait` as an (k, 3) array of robot,
/// task, wait.
fn evaluation_dict<'py>(py: Python<'py>, run: &Evaluation) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("makespan", run.makespan)?;
    d.set_item("travel", run.travel)?;
    d.set_item("waiting", run.waiting)?;
    d.set_item("longest_wait", run.longest_wait)?;
    d.set_item("max_wait", run.max_wait)?;
    d.set_item("valid", run.is_valid())?;
    d.set_item("start", run.start.clone().into_pyarray(py))?;
    d.set_item("finish", run.finish.clone().into_pyarray(py))?;
    d.set_item("back", run.back.clone().into_pyarray(py))?;
    let use_ = run.time_use();
    let time_use = PyDict::new(py);
    time_use.set_item("working", use_.working)?;
    time_use.set_item("driving", use_.driving)?;
    time_use.set_item("waiting", use_.waiting)?;
    time_use.set_item("idle", use_.idle)?;
    d.set_item("time_use", time_use)?;
    let flat: Vec<f64> = run
        .long_waits
        .iter()
        .flat_map(|w| [w.robot as f64, w.task as f64, w.wait])
        .collect();
    let long = numpy::ndarray::Array2::from_shape_vec((run.long_waits.len(), 3), flat)
        .expect("three per wait");
    d.set_item("long_waits", long.into_pyarray(py))?;
    Ok(d)
}

/// Plans a schedule: a dict with `routes` (one int64 array per robot), the evaluator's
/// numbers (`makespan`, `travel`, `waiting`, `longest_wait`, `start`, `finish`, …), the
/// certified `bound` and `gap`, and the search's `steps` and `seconds`. `start`: routes
/// to improve (the search starts from them and keeps them where it finds nothing
/// better). The GIL is released while it searches.
#[pyfunction]
#[pyo3(signature = (instance, time_limit=None, steps=None, seed=0, max_wait=None, start=None))]
fn schedule<'py>(
    py: Python<'py>,
    instance: &PyScheduleInstance,
    time_limit: Option<f64>,
    steps: Option<u64>,
    seed: u64,
    max_wait: Option<f64>,
    start: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let inst = Arc::clone(&instance.inner);
    let options = SolveOptions {
        time_limit,
        steps,
        seed,
        max_wait,
        start: start.map(routes_from).transpose()?,
    };
    let (solved, bound) = py
        .detach(|| -> Result<_, ScheduleError> { Ok((inst.solve(&options)?, inst.lower_bound())) })
        .map_err(schedule_error)?;
    let d = evaluation_dict(py, &solved.run)?;
    let routes: Vec<Bound<'py, PyArray1<i64>>> = solved
        .schedule
        .routes
        .iter()
        .map(|r| {
            r.iter()
                .map(|&j| j as i64)
                .collect::<Vec<_>>()
                .into_pyarray(py)
        })
        .collect();
    d.set_item("routes", routes)?;
    d.set_item("bound", bound.makespan)?;
    d.set_item("gap", bound.gap(solved.makespan()))?;
    d.set_item("steps", solved.steps)?;
    d.set_item("seconds", solved.seconds)?;
    Ok(d)
}

/// Plays anyone's schedule (one sequence of task ids per robot) under the instance's
/// rules and `max_wait` (or the one given): a dict as `schedule` returns, less the search.
/// A schedule that deadlocks, names an unknown task or leaves one out raises
/// `afg.InvalidInputError` saying who waits where.
#[pyfunction]
#[pyo3(signature = (instance, routes, max_wait=None))]
fn score_schedule<'py>(
    py: Python<'py>,
    instance: &PyScheduleInstance,
    routes: &Bound<'py, PyAny>,
    max_wait: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let schedule = routes_from(routes)?;
    let inst = &instance.inner;
    let run = inst
        .evaluate_with(&schedule, max_wait.unwrap_or(inst.max_wait))
        .map_err(schedule_error)?;
    evaluation_dict(py, &run)
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyScheduleInstance>()?;
    m.add_function(wrap_pyfunction!(schedule, m)?)?;
    m.add_function(wrap_pyfunction!(score_schedule, m)?)?;
    Ok(())
}

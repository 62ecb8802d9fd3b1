//! Missions for Python: `afg.Mission` (read, drawn, written) and `afg.run_mission`
//! (one allocator in the loop), with metrics as a dict and the timeline and decisions
//! as numpy arrays.

use std::path::PathBuf;
use std::str::FromStr;
use std::sync::Arc;

use afg_baseline::Network;
use afg_eval::mission::{MissionMethod, Planner};
use afg_game::Preference;
use afg_graph::GraphKind;
use afg_learn::run::ModelOptions;
use afg_mission::{
    Decentralised, Latency, Metrics, Mission, MissionConfig, MissionRun, Preset, RunOptions,
    TraceEvent,
};
use numpy::ndarray::{Array1, Array2};
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::value_error;

/// A mission: robots (positions, speeds), tasks that appear with a workload, failures,
/// β and a horizon (validated on construction).
#[pyclass(name = "Mission", module = "afg", frozen)]
pub(crate) struct PyMission {
    pub(crate) inner: Arc<Mission>,
}

#[pymethods]
impl PyMission {
    /// Reads a mission file (format "afg-mission"), as `afg mission gen` writes it.
    #[staticmethod]
    fn from_json(path: PathBuf) -> PyResult<Self> {
        let text = std::fs::read_to_string(&path).map_err(|source| {
            crate::game_error(afg_game::GameError::Io {
                path: path.display().to_string(),
                source,
            })
        })?;
        let mission = Mission::from_json(&text)
            .map_err(|e| PyValueError::new_err(format!("{}: {e}", path.display())))?;
        Ok(PyMission {
            inner: Arc::new(mission),
        })
    }

    /// Parses a mission document from a string.
    #[staticmethod]
    fn parse(text: &str) -> PyResult<Self> {
        Ok(PyMission {
            inner: Arc::new(Mission::from_json(text).map_err(value_error)?),
        })
    }

    /// Draws a mission: `preset` is "static", "waves", "poisson" or "attrition"; every
    /// knob as `afg mission gen` has it.
    #[staticmethod]
    #[pyo3(signature = (preset, robots, tasks, seed=0, workload=(1.0, 3.0), speed=1.0, arena=1.0, horizon=40.0, waves=4, interval=5.0, rate=None, fail_share=0.3, capacity_slack=None, allow_void=false))]
    // Python's keyword arguments, one per knob.
    #[allow(clippy::too_many_arguments)]
    fn generate(
        preset: &str,
        robots: usize,
        tasks: usize,
        seed: u64,
        workload: (f64, f64),
        speed: f64,
        arena: f64,
        horizon: f64,
        waves: usize,
        interval: f64,
        rate: Option<f64>,
        fail_share: f64,
        capacity_slack: Option<f64>,
        allow_void: bool,
    ) -> PyResult<Self> {
        let mut config = MissionConfig::new(crate::named::<Preset>(preset)?, robots, tasks, seed);
        (config.workload_min, config.workload_max) = workload;
        config.speed = speed;
        config.arena = arena;
        config.horizon = horizon;
        config.waves = waves;
        config.interval = interval;
        if let Some(rate) = rate {
            config.rate = rate;
        }
        config.fail_share = fail_share;
        config.capacity_slack = capacity_slack;
        config.allow_void = allow_void;
        Ok(PyMission {
            inner: Arc::new(config.generate().map_err(value_error)?),
        })
    }

    /// The mission file's text (one line of JSON).
    fn to_json(&self) -> String {
        self.inner.to_json()
    }

    /// Writes the mission file (atomically).
    fn write(&self, path: PathBuf) -> PyResult<()> {
        afg_game::fs::write_atomic(&path, (self.inner.to_json() + "\n").as_bytes())
            .map_err(crate::game_error)
    }

    #[getter]
    fn num_robots(&self) -> usize {
        self.inner.robots.len()
    }

    #[getter]
    fn num_tasks(&self) -> usize {
        self.inner.tasks.len()
    }

    #[getter]
    fn horizon(&self) -> f64 {
        self.inner.horizon
    }

    /// (N, 2) start positions.
    #[getter]
    fn robot_positions<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        points(self.inner.robots.iter().map(|r| r.position)).into_pyarray(py)
    }

    /// (K, 2) task positions.
    #[getter]
    fn task_positions<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        points(self.inner.tasks.iter().map(|t| t.position)).into_pyarray(py)
    }

    /// (K,) appearance times.
    #[getter]
    fn appears<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let v: Vec<f64> = self.inner.tasks.iter().map(|t| t.appears).collect();
        v.into_pyarray(py)
    }

    /// (K,) workloads.
    #[getter]
    fn workloads<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let v: Vec<f64> = self.inner.tasks.iter().map(|t| t.workload).collect();
        v.into_pyarray(py)
    }

    fn __eq__(&self, other: &Self) -> bool {
        self.inner == other.inner
    }

    /// Pickles through the mission's JSON document.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, (String,))> {
        crate::reduce_to::<PyMission>(py, "parse", self.inner.to_json())
    }

    fn __repr__(&self) -> String {
        format!(
            "Mission(robots={}, tasks={}, failures={}, horizon={})",
            self.inner.robots.len(),
            self.inner.tasks.len(),
            self.inner.failures.len(),
            self.inner.horizon
        )
    }
}

fn points(ps: impl ExactSizeIterator<Item = afg_game::Point>) -> Array2<f64> {
    let n = ps.len();
    let flat: Vec<f64> = ps.flat_map(|p| [p.x, p.y]).collect();
    Array2::from_shape_vec((n, 2), flat).expect("two coordinates per point")
}

/// One run of a mission: its metrics, its timeline and (if asked) its decisions.
#[pyclass(name = "MissionResult", module = "afg", frozen)]
#[derive(serde::Serialize, serde::Deserialize)]
pub(crate) struct PyMissionResult {
    run: MissionRun,
    robots: usize,
}

#[pymethods]
impl PyMissionResult {
    /// The run's metrics (docs/missions.md defines each): a dict.
    #[getter]
    fn metrics<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        metrics_dict(py, &self.run.metrics)
    }

    /// The mission after every event: a dict of (T,) arrays `time`, `open`, `done`,
    /// `reward`.
    #[getter]
    fn timeline<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let t = &self.run.timeline;
        let d = PyDict::new(py);
        let column =
            |f: fn(&afg_mission::TimelinePoint) -> f64| -> Vec<f64> { t.iter().map(f).collect() };
        d.set_item("time", column(|p| p.time).into_pyarray(py))?;
        d.set_item(
            "open",
            t.iter()
                .map(|p| p.open as i64)
                .collect::<Vec<_>>()
                .into_pyarray(py),
        )?;
        d.set_item(
            "done",
            t.iter()
                .map(|p| p.done as i64)
                .collect::<Vec<_>>()
                .into_pyarray(py),
        )?;
        d.set_item("reward", column(|p| p.reward).into_pyarray(py))?;
        Ok(d)
    }

    /// The decisions (with `trace=True`): `(time (D,), tasks (D, N) int64, -1 for none)`.
    #[getter]
    fn decisions<'py>(
        &self,
        py: Python<'py>,
    ) -> (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray2<i64>>) {
        let mut times = Vec::new();
        let mut rows: Vec<i64> = Vec::new();
        for e in &self.run.trace {
            if let TraceEvent::Decision { time, tasks, .. } = e {
                times.push(*time);
                rows.extend(tasks);
            }
        }
        let d = times.len();
        let tasks = Array2::from_shape_vec((d, self.robots), rows).expect("N tasks per decision");
        (Array1::from(times).into_pyarray(py), tasks.into_pyarray(py))
    }

    /// Every event and decision (with `trace=True`), as the JSON Lines of `--trace`.
    fn trace_jsonl(&self) -> String {
        self.run.trace_jsonl()
    }

    /// Pickles through the run's own JSON document (nothing is run again).
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, (String,))> {
        let document = serde_json::to_string(self).map_err(value_error)?;
        crate::reduce_to::<PyMissionResult>(py, "_from_state", document)
    }

    /// The result of a pickled document (`__reduce__`).
    #[staticmethod]
    fn _from_state(text: &str) -> PyResult<Self> {
        serde_json::from_str(text).map_err(value_error)
    }

    fn __repr__(&self) -> String {
        let m = &self.run.metrics;
        format!(
            "MissionResult(tasks_done={}/{}, reward_done={:.3}, decisions={})",
            m.tasks_done, m.tasks, m.reward_done, m.decisions
        )
    }
}

fn metrics_dict<'py>(py: Python<'py>, m: &Metrics) -> PyResult<Bound<'py, PyDict>> {
    let value = serde_json::to_value(m).map_err(value_error)?;
    object_dict(py, &value)
}

/// A JSON object of numbers, nulls and such objects (the metrics) as a dict.
fn object_dict<'py>(py: Python<'py>, value: &serde_json::Value) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (k, v) in value.as_object().expect("metrics are an object") {
        match v {
            serde_json::Value::Null => d.set_item(k, py.None())?,
            serde_json::Value::Number(x) if x.is_u64() => d.set_item(k, x.as_u64())?,
            serde_json::Value::Number(x) => d.set_item(k, x.as_f64())?,
            serde_json::Value::Object(_) => d.set_item(k, object_dict(py, v)?)?,
            other => d.set_item(k, other.to_string())?,
        }
    }
    Ok(d)
}

/// Runs `mission` with one allocator in the loop: a built-in method (default "opt")
/// or a trained model's run directory; `warm=True` warm-starts every decision after
/// the first (the optimum from its previous prices); `replan=T` also decides every T;
/// `latency=D` makes each decision take D time units, `latency_factor=F` the
/// allocator's measured compute time times F; `commit=True` keeps robots at work until
/// their task is done, `hysteresis=THETA` lets a travelling robot switch only for a
/// gain above THETA; `trace=True` keeps every decision.
///
/// `method="grape"` (or `"auction"`) has the robots run GRAPE (or the auction)
/// themselves over the radio:
/// `rounds_per_time` rounds per time unit, links between robots within `radius` (else
/// to their 10 nearest) re-evaluated as they move, a share `loss` of messages lost,
/// and tasks seen within `sensing` (else heard of at once); its metrics gain a
/// "swarm" dict (rounds, messages, bytes, response times).
#[pyfunction]
#[pyo3(signature = (mission, method=None, model=None, warm=false, replan=None, latency=None, latency_factor=None, commit=false, hysteresis=None, seed=0, trace=false, rounds_per_time=100.0, radius=None, loss=0.0, sensing=None))]
// Python's keyword arguments, one per option.
#[allow(clippy::too_many_arguments)]
pub(crate) fn run_mission(
    py: Python<'_>,
    mission: &PyMission,
    method: Option<&str>,
    model: Option<PathBuf>,
    warm: bool,
    replan: Option<f64>,
    latency: Option<f64>,
    latency_factor: Option<f64>,
    commit: bool,
    hysteresis: Option<f64>,
    seed: u64,
    trace: bool,
    rounds_per_time: f64,
    radius: Option<f64>,
    loss: f64,
    sensing: Option<f64>,
) -> PyResult<PyMissionResult> {
    let planner = match (method, model) {
        (_, Some(dir)) if method.is_some() => {
            return Err(PyValueError::new_err(format!(
                "pass method= or model=, not both (model={})",
                dir.display()
            )));
        }
        (_, Some(dir)) => {
            Planner::model(&dir, ModelOptions::default(), warm).map_err(value_error)?
        }
        (name, None) => match MissionMethod::from_str(name.unwrap_or("opt")) {
            Ok(MissionMethod::Central(method)) => Planner::method(method, seed, warm),
            Ok(swarm) => {
                let method = (swarm.swarm(Preference::Selfish, 1e-3))
                    .expect("a method that is not central is decentralised");
                let mut network = Network {
                    loss,
                    ..Network::default()
                };
                if let Some(radius) = radius {
                    network.graph = GraphKind::Radius { radius };
                }
                Planner::swarm(Decentralised {
                    rounds_per_time,
                    sensing,
                    seed,
                    ..Decentralised::new(method, network)
                })
            }
            Err(message) => return Err(PyValueError::new_err(message)),
        },
    };
    let latency = match (latency, latency_factor) {
        (Some(_), Some(_)) => {
            return Err(PyValueError::new_err(
                "pass latency= or latency_factor=, not both",
            ));
        }
        (Some(delay), None) => Latency::Fixed { delay },
        (None, Some(factor)) => Latency::Measured { factor },
        (None, None) => Latency::None,
    };
    let options = RunOptions {
        replan_every: replan,
        latency,
        trace,
        commit,
        hysteresis,
        ..RunOptions::default()
    };
    let inner = Arc::clone(&mission.inner);
    let run = py
        .detach(|| planner.run(&inner, options))
        .map_err(value_error)?;
    Ok(PyMissionResult {
        run,
        robots: mission.inner.robots.len(),
    })
}

/// Adds the mission classes and `run_mission`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyMission>()?;
    m.add_class::<PyMissionResult>()?;
    m.add_function(wrap_pyfunction!(run_mission, m)?)?;
    Ok(())
}

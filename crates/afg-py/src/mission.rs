//! Missions for Python: `afg.Mission` (read, drawn, written) and `afg.run_mission`
//! (one allocator in the loop), with metrics as a dict and the timeline and decisions
//! as numpy arrays.

use std::path::PathBuf;
use std::str::FromStr;
use std::sync::Arc;

use afg_eval::mission::planner;
use afg_mission::{
    Latency, Metrics, Mission, MissionKnobs, MissionMethod, MissionPlan, MissionRun, Preset,
    RadioKnobs, Recording, SwarmKnobs, TraceEvent,
};
use numpy::ndarray::{Array1, Array2};
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::args::{FloatPair, Whole, WholePair};
use crate::bad_input;

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
            crate::crate_error(afg_game::GameError::Io {
                path: path.display().to_string(),
                source,
            })
        })?;
        let mission = Mission::from_json(&text)
            .map_err(|e| crate::bad_input(format!("{}: {e}", path.display())))?;
        Ok(PyMission {
            inner: Arc::new(mission),
        })
    }

    /// Parses a mission document from a string.
    #[staticmethod]
    fn parse(text: &str) -> PyResult<Self> {
        Ok(PyMission {
            inner: Arc::new(Mission::from_json(text).map_err(bad_input)?),
        })
    }

    /// Draws a mission: `preset` is "static", "waves", "poisson" or "attrition"; every
    /// knob as `afg mission gen` has it, under the same name; a knob left at None
    /// takes its default (`afg.mission_defaults()["generate"]`).
    #[staticmethod]
    #[pyo3(signature = (preset, robots, tasks, seed=Whole(0), workload=None, speed=None, arena=None, horizon=None, waves=None, interval=None, rate=None, fail_share=None, capacity_slack=None, allow_void=false, min_team=None, skills=None, skill_share=None, requires=None))]
    // Python's keyword arguments, one per knob.
    #[allow(clippy::too_many_arguments)]
    fn generate(
        py: Python<'_>,
        preset: &str,
        robots: Whole,
        tasks: Whole,
        seed: Whole,
        workload: Option<FloatPair>,
        speed: Option<f64>,
        arena: Option<f64>,
        horizon: Option<f64>,
        waves: Option<Whole>,
        interval: Option<f64>,
        rate: Option<f64>,
        fail_share: Option<f64>,
        capacity_slack: Option<f64>,
        allow_void: bool,
        min_team: Option<WholePair>,
        skills: Option<Whole>,
        skill_share: Option<f64>,
        requires: Option<WholePair>,
    ) -> PyResult<Self> {
        let d = MissionKnobs::default();
        let knobs = MissionKnobs {
            workload: workload.map_or(d.workload, |FloatPair(lo, hi)| (lo, hi)),
            speed: speed.unwrap_or(d.speed),
            arena: arena.unwrap_or(d.arena),
            horizon: horizon.unwrap_or(d.horizon),
            waves: waves.map(|w| w.count()).transpose()?.unwrap_or(d.waves),
            interval: interval.unwrap_or(d.interval),
            rate,
            fail_share: fail_share.unwrap_or(d.fail_share),
            capacity_slack,
            allow_void,
            min_team: min_team.map(|WholePair(lo, hi)| (lo, hi)),
            skills: skills.map(|s| s.count()).transpose()?,
            skill_share,
            requires: requires.map(|WholePair(lo, hi)| (lo, hi)),
        };
        let config = knobs.config(
            crate::named::<Preset>(preset)?,
            robots.count()?,
            tasks.count()?,
            seed.0,
        );
        let mission = config.generate().map_err(bad_input)?;
        crate::warn(
            py,
            afg_game::unstaffable_warning(&mission.unstaffable_tasks()),
        )?;
        Ok(PyMission {
            inner: Arc::new(mission),
        })
    }

    /// The mission file's text (one line of JSON).
    fn to_json(&self) -> String {
        self.inner.to_json()
    }

    /// Writes the mission file (atomically).
    fn write(&self, path: PathBuf) -> PyResult<()> {
        afg_game::fs::write_atomic(&path, (self.inner.to_json() + "\n").as_bytes())
            .map_err(crate::crate_error)
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

    /// (K,) each task's threshold (1 where none).
    #[getter]
    fn min_team<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        let v: Vec<i64> = self.inner.tasks.iter().map(|t| t.min_team as i64).collect();
        v.into_pyarray(py)
    }

    /// (N, S) each robot's amount of each skill (S = 0 without skills).
    #[getter]
    fn skills<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<i64>> {
        let rows = self.inner.robots.iter().map(|r| r.skills.as_slice());
        crate::skill_matrix(py, rows, self.inner.robots.len(), self.inner.num_skills())
    }

    /// (K, S) what each task requires of each skill.
    #[getter]
    fn requires<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<i64>> {
        let s = self.inner.num_skills();
        let rows: Vec<Vec<u32>> = (self.inner.tasks.iter())
            .map(|t| {
                (0..s)
                    .map(|k| t.requires.get(k).copied().unwrap_or(0))
                    .collect()
            })
            .collect();
        crate::skill_matrix(py, rows.iter().map(Vec::as_slice), rows.len(), s)
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
        let document = serde_json::to_string(self).map_err(bad_input)?;
        crate::reduce_to::<PyMissionResult>(py, "_from_state", document)
    }

    /// The result of a pickled document (`__reduce__`).
    #[staticmethod]
    fn _from_state(text: &str) -> PyResult<Self> {
        serde_json::from_str(text).map_err(bad_input)
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
    let value = serde_json::to_value(m).map_err(bad_input)?;
    object_dict(py, &value)
}

/// A JSON object of numbers, nulls, lists of numbers (numpy arrays) and such objects
/// (the metrics) as a dict.
fn object_dict<'py>(py: Python<'py>, value: &serde_json::Value) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (k, v) in value.as_object().expect("metrics are an object") {
        match v {
            serde_json::Value::Null => d.set_item(k, py.None())?,
            serde_json::Value::Number(x) if x.is_u64() => d.set_item(k, x.as_u64())?,
            serde_json::Value::Number(x) => d.set_item(k, x.as_f64())?,
            serde_json::Value::Object(_) => d.set_item(k, object_dict(py, v)?)?,
            serde_json::Value::Array(items) => {
                let numbers: Vec<f64> =
                    items.iter().filter_map(serde_json::Value::as_f64).collect();
                d.set_item(k, PyArray1::from_vec(py, numbers))?;
            }
            other => d.set_item(k, other.to_string())?,
        }
    }
    Ok(d)
}

/// Runs `mission` with one allocator in the loop, with every knob of `afg mission run`
/// under the same name (docs/missions.md): a built-in method (default "opt") or a
/// trained model's run directory; `warm=True` warm-starts every decision after the
/// first (the optimum from its previous prices); `replan=T` also decides every T;
/// `latency=D` makes each decision take D time units, `latency_factor=F` the
/// allocator's measured compute time times F; `commit=True` keeps robots at work until
/// their task is done, `hysteresis=THETA` lets a travelling robot switch only for a
/// gain above THETA; `time_limit=SECS` stops the exact optimum at each decision with
/// the best found (its gaps in the metrics' `gap_max`); `trace=True` keeps every
/// decision.
///
/// `method="grape"` (or `"auction"`) has the robots run GRAPE (or the auction)
/// themselves over the radio: `rounds_per_time` rounds per time unit, GRAPE's
/// `preference`, the auction's `epsilon`, links between robots within `radius` (else
/// to their `knn` nearest) re-evaluated as they move, a share `loss` of messages lost
/// (in bursts of mean length `burst`), each arriving up to `delay` rounds late, robots
/// awake in a round with chance `activation`, and tasks seen within `sensing` (else
/// heard of at once); its metrics gain a "swarm" dict (rounds, messages, bytes,
/// response times). A swarm knob left at None takes its default
/// (`afg.mission_defaults()`; `epsilon` is 0.01 instead where the mission's tasks
/// need teams or skills); one set with a central method is refused.
#[pyfunction]
#[pyo3(signature = (mission, method=None, model=None, warm=false, replan=None, latency=None, latency_factor=None, commit=false, hysteresis=None, time_limit=None, seed=0, trace=false, rounds_per_time=None, loss=None, sensing=None, preference=None, epsilon=None, radius=None, knn=None, burst=None, delay=None, activation=None))]
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
    time_limit: Option<f64>,
    seed: u64,
    trace: bool,
    rounds_per_time: Option<f64>,
    loss: Option<f64>,
    sensing: Option<f64>,
    preference: Option<&str>,
    epsilon: Option<f64>,
    radius: Option<f64>,
    knn: Option<usize>,
    burst: Option<f64>,
    delay: Option<u32>,
    activation: Option<f64>,
) -> PyResult<PyMissionResult> {
    if let (Some(_), Some(dir)) = (method, &model) {
        return Err(crate::bad_input(format!(
            "pass method= or model=, not both (model={})",
            dir.display()
        )));
    }
    let latency = Latency::from_knobs(latency, latency_factor).map_err(crate::bad_input)?;
    let defaults = SwarmKnobs::default();
    let radio = RadioKnobs {
        radius,
        knn: knn.unwrap_or(defaults.radio.knn),
        loss: loss.unwrap_or(defaults.radio.loss),
        burst,
        delay: delay.unwrap_or(defaults.radio.delay),
        activation: activation.unwrap_or(defaults.radio.activation),
    };
    let method = MissionMethod::from_str(method.unwrap_or("opt")).map_err(crate::bad_input)?;
    let plan = MissionPlan {
        method,
        warm,
        seed,
        swarm: SwarmKnobs {
            preference: preference.map_or(Ok(defaults.preference), crate::named)?,
            epsilon: epsilon.unwrap_or_else(|| {
                SwarmKnobs::default_epsilon(method, mission.inner.needs_teams())
            }),
            radio,
            rounds_per_time: rounds_per_time.unwrap_or(defaults.rounds_per_time),
            sensing,
        },
        replan_every: replan,
        latency,
        commit,
        hysteresis,
        time_limit,
    };
    let planner = planner(&plan, model.as_deref()).map_err(crate::crate_error)?;
    crate::warn(py, plan.advice(&mission.inner))?;
    let inner = Arc::clone(&mission.inner);
    let recording = Recording {
        trace,
        frame_every: None,
    };
    let run = py
        .detach(|| planner.run(&inner, recording, |_| {}))
        .map_err(crate::bad_input)?;
    Ok(PyMissionResult {
        run,
        robots: mission.inner.robots.len(),
    })
}

/// The defaults of the knobs left at None: `{"run": {...}, "generate": {...}}`, those
/// of `run_mission`'s swarm knobs and of `Mission.generate`.
#[pyfunction]
pub(crate) fn mission_defaults(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let knobs = SwarmKnobs::default();
    let run = PyDict::new(py);
    run.set_item("rounds_per_time", knobs.rounds_per_time)?;
    run.set_item("loss", knobs.radio.loss)?;
    run.set_item("sensing", knobs.sensing)?;
    run.set_item("preference", afg_game::Named::name(knobs.preference))?;
    // It depends on the mission: SwarmKnobs::default_epsilon.
    run.set_item("epsilon", py.None())?;
    run.set_item("radius", knobs.radio.radius)?;
    run.set_item("knn", knobs.radio.knn)?;
    run.set_item("burst", knobs.radio.burst)?;
    run.set_item("delay", knobs.radio.delay)?;
    run.set_item("activation", knobs.radio.activation)?;
    let drawn = MissionKnobs::default();
    let generate = PyDict::new(py);
    generate.set_item("workload", drawn.workload)?;
    generate.set_item("speed", drawn.speed)?;
    generate.set_item("arena", drawn.arena)?;
    generate.set_item("horizon", drawn.horizon)?;
    generate.set_item("waves", drawn.waves)?;
    generate.set_item("interval", drawn.interval)?;
    generate.set_item("rate", drawn.rate)?;
    generate.set_item("fail_share", drawn.fail_share)?;
    generate.set_item("capacity_slack", drawn.capacity_slack)?;
    generate.set_item("min_team", drawn.min_team)?;
    generate.set_item("skills", drawn.skills)?;
    generate.set_item("skill_share", drawn.skill_share)?;
    generate.set_item("requires", drawn.requires)?;
    let d = PyDict::new(py);
    d.set_item("run", run)?;
    d.set_item("generate", generate)?;
    Ok(d)
}

/// Adds the mission classes and `run_mission`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyMission>()?;
    m.add_class::<PyMissionResult>()?;
    m.add_function(wrap_pyfunction!(run_mission, m)?)?;
    m.add_function(wrap_pyfunction!(mission_defaults, m)?)?;
    Ok(())
}

//! Allocators from Python: `solve`, `load_model`, `reallocate` and `q_star`.

use std::path::PathBuf;
use std::str::FromStr;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use afg_baseline::{Allocator, Method, TeamOptimum};
use afg_eval::scorecard::{Scorecard, scorecard};
use afg_eval::solve::{Against, Row};
use afg_game::Preference;
use afg_game::realloc::PreviousAssignment;
use afg_game::{RobotId, TaskId};
use afg_learn::run::{ModelOptions, load_model as load_dir};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::interrupt::interruptible;
use crate::{IntVector, PyInstance, bad_input, task_ids, task_indices};

/// An allocation of one instance, scored against the exact optimum.
#[pyclass(name = "Result", module = "afg", frozen)]
#[derive(serde::Serialize, serde::Deserialize)]
pub struct SolveResult {
    tasks: Vec<i64>,
    card: Scorecard,
    /// Extra figures, by name (the allocator's statistics, or a reallocation's).
    stats: Vec<(String, f64)>,
}

fn alloc_stats(row: &Row) -> Vec<(String, f64)> {
    let s = &row.stats;
    let mut stats: Vec<(String, f64)> = [
        ("iterations", s.iterations as f64),
        ("rounds", s.rounds as f64),
        ("messages", s.messages as f64),
        ("wall_time_s", s.wall_time.as_secs_f64()),
    ]
    .map(|(k, v)| (k.to_owned(), v))
    .to_vec();
    if let (Some(bound), Some(gap)) = (s.bound, row.gap) {
        stats.push(("bound".into(), bound));
        stats.push(("gap".into(), gap));
    }
    if let Some(reference) = row.reference {
        stats.push(("reference_welfare".into(), reference.welfare));
        stats.push(("reference_bound".into(), reference.bound));
        stats.push((
            "reference_proven".into(),
            f64::from(u8::from(reference.proven)),
        ));
    }
    stats
}

#[pymethods]
impl SolveResult {
    /// Pickles through the result's own JSON document (nothing is recomputed).
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, (String,))> {
        let document = serde_json::to_string(self).map_err(bad_input)?;
        crate::reduce_to::<SolveResult>(py, "_from_state", document)
    }

    /// The result of a pickled document (`__reduce__`).
    #[staticmethod]
    fn _from_state(text: &str) -> PyResult<Self> {
        serde_json::from_str(text).map_err(bad_input)
    }

    /// Robot i's task, shape (N,), int64 (-1 for none).
    #[getter]
    fn tasks<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        self.tasks.clone().into_pyarray(py)
    }
    /// Welfare of the allocation.
    #[getter]
    fn welfare(&self) -> f64 {
        self.card.score.welfare
    }
    /// Welfare of the exact optimum.
    #[getter]
    fn opt_welfare(&self) -> f64 {
        self.card.score.opt_welfare
    }
    /// 100 · welfare / opt_welfare; None when the optimum's welfare is not positive.
    #[getter]
    fn percent_of_opt(&self) -> Option<f64> {
        self.card.score.percent_of_opt
    }
    /// Share of robots (0..=1) with no strictly preferred move, balanced preference.
    #[getter]
    fn ns_rate_balanced(&self) -> f64 {
        self.card.score.ns_rate_balanced
    }
    /// The same under the selfish (GRAPE) preference.
    #[getter]
    fn ns_rate_selfish(&self) -> f64 {
        self.card.score.ns_rate_selfish
    }
    /// Robots in each task's coalition, shape (M,), int64.
    #[getter]
    fn coalition_sizes<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        let sizes: Vec<i64> = self
            .card
            .coalition_sizes
            .iter()
            .map(|&n| n as i64)
            .collect();
        sizes.into_pyarray(py)
    }
    /// Robots in no coalition.
    #[getter]
    fn unassigned(&self) -> usize {
        self.card.unassigned
    }
    /// Whether no robot would move under the balanced preference (Def. 3).
    #[getter]
    fn stable_balanced(&self) -> bool {
        self.card.stable_balanced
    }
    /// Whether no robot would move under the selfish (GRAPE) preference.
    #[getter]
    fn stable_selfish(&self) -> bool {
        self.card.stable_selfish
    }
    /// The robots that would move under `preference` ("balanced" or "selfish"), shape
    /// (K, 3), int64: each row a robot, its task now (-1: none) and the task it would
    /// take.
    #[pyo3(signature = (preference="balanced"))]
    fn moves<'py>(&self, py: Python<'py>, preference: &str) -> PyResult<Bound<'py, PyArray2<i64>>> {
        let moves = match crate::named::<Preference>(preference)? {
            Preference::Balanced => &self.card.moves_balanced,
            Preference::Selfish => &self.card.moves_selfish,
        };
        let rows: Vec<i64> = moves
            .iter()
            .flat_map(|m| [i64::from(m.robot), m.from, m.to])
            .collect();
        let array = Array2::from_shape_vec((moves.len(), 3), rows).expect("three columns a move");
        Ok(array.into_pyarray(py))
    }
    /// What the allocator reported (iterations, rounds, messages, wall_time_s; core_s:
    /// the crates' whole part of a solve, the method and the optimum), or a
    /// reallocation's figures (survivors, moved, placed, …).
    #[getter]
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (k, v) in &self.stats {
            d.set_item(k, v)?;
        }
        Ok(d)
    }
    fn __repr__(&self) -> String {
        let pct = self
            .card
            .score
            .percent_of_opt
            .map_or("None".to_owned(), |p| format!("{p:.2}"));
        format!(
            "Result(welfare={:.4}, opt_welfare={:.4}, percent_of_opt={pct})",
            self.card.score.welfare, self.card.score.opt_welfare
        )
    }
}

/// A trained model of a run directory, as an allocator.
#[pyclass(name = "Model", module = "afg", frozen)]
pub struct PyModel {
    allocator: Box<dyn Allocator>,
    path: String,
    /// `load_model`'s options: block, repair, one_shot.
    options: (Option<usize>, bool, bool),
}

#[pymethods]
impl PyModel {
    /// Allocates one instance (the GIL is released while it runs), measured against
    /// the optimum as `afg.solve` is (`reference`, `reference_time_limit`).
    #[pyo3(signature = (instance, reference=true, reference_time_limit=10.0))]
    fn allocate(
        &self,
        py: Python<'_>,
        instance: &PyInstance,
        reference: bool,
        reference_time_limit: f64,
    ) -> PyResult<SolveResult> {
        let against = against(reference, reference_time_limit)?;
        run(
            py,
            instance,
            self.allocator.as_ref(),
            against,
            &AtomicBool::default(),
        )
    }
    fn __repr__(&self) -> String {
        format!("Model({:?})", self.path)
    }

    /// Pickles as the directory and options to load it again.
    #[allow(clippy::type_complexity)]
    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, (String, Option<usize>, bool, bool))> {
        let load = py.import("afg._afg")?.getattr("load_model")?;
        let (block, repair, one_shot) = self.options;
        Ok((load, (self.path.clone(), block, repair, one_shot)))
    }
}

/// Loads the trained model of a run directory: a Q network, a price model or a staffing
/// model. `repair`: balanced best-response sweeps after a Q network's rollout, or a
/// welfare climb after a staffing model's placement (ours).
#[pyfunction]
#[pyo3(signature = (path, block=None, repair=false, one_shot=false))]
fn load_model(
    path: PathBuf,
    block: Option<usize>,
    repair: bool,
    one_shot: bool,
) -> PyResult<PyModel> {
    if !path.is_dir() {
        return Err(crate::missing_file(format!(
            "{}: no such model directory",
            path.display()
        )));
    }
    let options = ModelOptions {
        block,
        repair,
        one_shot,
        exact_burn: false,
    };
    Ok(PyModel {
        allocator: load_dir(&path, options).map_err(bad_input)?,
        path: path.display().to_string(),
        options: (block, repair, one_shot),
    })
}

/// What a result is measured against: the optimum within `time_limit` seconds on a
/// team game (of its bound where not proven), or nothing.
fn against(reference: bool, time_limit: f64) -> PyResult<Against> {
    if !reference {
        return Ok(Against::Nothing);
    }
    Against::optimum_within(time_limit)
        .map_err(|e| crate::bad_input(format!("reference_time_limit: {e}")))
}

/// Allocates and scores `instance` off the interpreter's lock; Ctrl-C sets `stop`
/// (which the exact solver reads: see [`interruptible`]).
fn run(
    py: Python<'_>,
    instance: &PyInstance,
    allocator: &dyn Allocator,
    against: Against,
    stop: &AtomicBool,
) -> PyResult<SolveResult> {
    let inst = &instance.inner;
    let start = Instant::now();
    let (row, assignment, card) = interruptible(py, stop, || {
        let (row, assignment) = Row::compute(inst, allocator, against)?;
        let card = Scorecard::with_score(inst, &assignment, row.score);
        Ok::<_, afg_eval::EvalError>((row, assignment, card))
    })?
    .map_err(bad_input)?;
    let mut stats = alloc_stats(&row);
    // The crates' whole part of the call (the method, the optimum it is scored
    // against, and its stability and NS rates), for measuring what the binding adds.
    stats.push(("core_s".into(), start.elapsed().as_secs_f64()));
    Ok(SolveResult {
        tasks: task_indices(&assignment),
        stats,
        card,
    })
}

fn method(name: &str) -> PyResult<Method> {
    Method::from_str(name).map_err(crate::bad_input)
}

/// Solves one instance by a built-in method (`opt`, `da`, `da-decentralised`,
/// `da-balanced`, `greedy`, `nearest`, `random`, `blind`) or a trained model (a run
/// directory or a loaded `Model`), scored against the exact optimum. `time_limit`
/// (seconds, `opt` only) stops the exact search with the best found, and so does a
/// certified `gap` target (`opt` only; 0.001: within 0.1 % of the bound) or Ctrl-C
/// (at the search's next step, then `KeyboardInterrupt`); `stats` then has its
/// proven `bound` and `gap`, as for every exact solve of a team game. `start`
/// (`opt` only: robot i's task, -1 for none, as `score` takes it) is the exact
/// search's first best found — another method's answer, an earlier solve's — so it
/// prunes from its first node and never answers worse. On a
/// team game the "% of OPT" solves the game exactly first, stopped after
/// `reference_time_limit` seconds (the share is then of its certified bound:
/// `stats["reference_proven"]` is 0); `reference=False` measures nothing.
#[pyfunction]
#[pyo3(signature = (instance, method=None, model=None, seed=0, time_limit=None, gap=None, reference=true, reference_time_limit=10.0, start=None))]
#[allow(clippy::too_many_arguments)]
fn solve(
    py: Python<'_>,
    instance: &PyInstance,
    method: Option<&str>,
    model: Option<&Bound<'_, PyAny>>,
    seed: u64,
    time_limit: Option<f64>,
    gap: Option<f64>,
    reference: bool,
    reference_time_limit: f64,
    start: Option<IntVector<'_>>,
) -> PyResult<SolveResult> {
    let against = against(reference, reference_time_limit)?;
    let method = method.map(self::method).transpose()?;
    let start = start.map(|tasks| instance.assignment(&tasks)).transpose()?;
    if start.is_some() && method != Some(Method::Opt) {
        return Err(crate::bad_input(
            "start: a start is for the exact optimum (method opt) only",
        ));
    }
    if (time_limit.is_some() || gap.is_some()) && method.is_none() {
        return Err(crate::bad_input(
            "time_limit / gap: a time limit or a gap is for the exact optimum (method opt) only",
        ));
    }
    match (method, model) {
        (Some(method), None) => {
            let stop = Arc::new(AtomicBool::new(false));
            let exact = (method.exact(time_limit, gap))
                .map(|exact| {
                    exact.map(|exact| TeamOptimum {
                        stop: Some(Arc::clone(&stop)),
                        start,
                        ..exact
                    })
                })
                .and_then(|exact| method.allocator_with(seed, exact))
                .map_err(|e| crate::bad_input(format!("time_limit / gap: {e}")))?;
            run(py, instance, exact.as_ref(), against, &stop)
        }
        (None, Some(model)) => {
            let loaded;
            let allocator = match model.cast::<PyModel>() {
                Ok(m) => m.get().allocator.as_ref(),
                Err(_) => {
                    loaded = load_model(model.extract()?, None, false, false)?;
                    loaded.allocator.as_ref()
                }
            };
            run(py, instance, allocator, against, &AtomicBool::default())
        }
        _ => Err(crate::bad_input(
            "pass exactly one of method=NAME or model=PATH_OR_MODEL",
        )),
    }
}

/// Scores a given assignment (`tasks[i]` = robot i's task) against the exact optimum,
/// as `afg score` does: the same scorecard, coalitions and moves included.
#[pyfunction]
fn score(py: Python<'_>, instance: &PyInstance, tasks: IntVector<'_>) -> PyResult<SolveResult> {
    let assignment = instance.assignment(&tasks)?;
    let inst = instance.inner.clone();
    let card = py
        .detach(|| scorecard(&inst, &assignment))
        .map_err(bad_input)?;
    Ok(SolveResult {
        tasks: task_indices(&assignment),
        card,
        stats: Vec::new(),
    })
}

/// The names of the built-in methods.
#[pyfunction]
fn methods() -> Vec<&'static str> {
    Method::ALL.iter().map(|m| m.name()).collect()
}

/// Warm start after robots or tasks changed: `previous_tasks` is the old assignment
/// (old robot indices), `left_robots` / `left_tasks` name what left; the instance keeps
/// the survivors in their old order, then newcomers. Survivors keep their task, the
/// others join by best response, then the dynamics of `method` (`da-balanced` or
/// `da`) settle.
#[pyfunction]
#[pyo3(signature = (instance, previous_tasks, left_robots=Vec::new(), left_tasks=Vec::new(), method="da-balanced"))]
fn reallocate(
    py: Python<'_>,
    instance: &PyInstance,
    previous_tasks: IntVector<'_>,
    left_robots: Vec<u32>,
    left_tasks: Vec<u32>,
    method: &str,
) -> PyResult<SolveResult> {
    let m = self::method(method)?;
    let preference = afg_eval::realloc::dynamics_after(m).ok_or_else(|| {
        crate::bad_input(format!(
            "reallocation runs best-response dynamics: method \"da-balanced\" or \"da\", not {method:?}"
        ))
    })?;
    let tasks = task_ids(&previous_tasks)?;
    let previous = PreviousAssignment {
        tasks,
        left_robots: left_robots.into_iter().map(RobotId).collect(),
        left_tasks: left_tasks.into_iter().map(TaskId).collect(),
    };
    let inst = instance.inner.clone();
    let r = py
        .detach(|| afg_eval::realloc::reallocate(&inst, &previous, preference))
        .map_err(bad_input)?;
    let score = afg_eval::Score::of("the reallocation", &inst, &r.assignment, r.opt_welfare)
        .map_err(bad_input)?;
    Ok(SolveResult {
        tasks: task_indices(&r.assignment),
        card: Scorecard::with_score(&inst, &r.assignment, score),
        stats: [
            ("survivors", r.survivors as f64),
            ("moved", r.moved as f64),
            ("placed", r.placed as f64),
            ("opt_changes", r.opt_changes as f64),
            ("scratch_changes", r.scratch_changes as f64),
            ("wall_time_s", r.seconds),
        ]
        .map(|(k, v)| (k.to_owned(), v))
        .to_vec(),
    })
}

/// Exact action values of the next robot: `tasks_so_far[i]` is the task of robot i
/// for the robots that have acted (robots act in index order); entry j of the result
/// is the welfare that taking task j and then completing optimally adds from now on,
/// -inf where task j has no room. Where the instance allows the void task, one more
/// entry last: the robot staying out; and `acted` says how many robots have acted
/// (a -1 among them stayed out).
#[pyfunction]
#[pyo3(signature = (instance, tasks_so_far, acted=None))]
fn q_star<'py>(
    py: Python<'py>,
    instance: &PyInstance,
    tasks_so_far: IntVector<'_>,
    acted: Option<usize>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let values = q_star_of(py, instance, tasks_so_far.to_vec(), acted)?;
    Ok(values.into_pyarray(py))
}

/// [`q_star`] as a vector: the robots that have acted are the first `acted` entries
/// (-1: stayed out) or, without `acted`, the entries before the first -1 (a whole
/// assignment vector with -1 for the rest is accepted too).
pub(crate) fn q_star_of(
    py: Python<'_>,
    instance: &PyInstance,
    tasks: Vec<i64>,
    acted: Option<usize>,
) -> PyResult<Vec<f64>> {
    let acted = acted.unwrap_or_else(|| tasks.iter().take_while(|&&t| t != -1).count());
    if acted > tasks.len() {
        return Err(crate::bad_input(format!(
            "acted = {acted}, but there are {} tasks",
            tasks.len()
        )));
    }
    if tasks[acted..].iter().any(|&t| t != -1) {
        return Err(crate::bad_input(
            "robots act in index order: no robot after those that acted may have a task",
        ));
    }
    let prefix = tasks[..acted]
        .iter()
        .map(|&t| match t {
            -1 => Ok(None),
            t => u32::try_from(t).map(|j| Some(TaskId(j))),
        })
        .collect::<Result<Vec<_>, _>>()
        .map_err(|_| crate::bad_input("a task is -1 or an index 0..M"))?;
    let inst = instance.inner.clone();
    let values = py
        .detach(|| afg_learn::policy::q_star_next(&inst, &prefix))
        .map_err(bad_input)?;
    Ok(values
        .into_iter()
        .map(|v| v.unwrap_or(f64::NEG_INFINITY))
        .collect())
}

/// Adds this module's classes and functions.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<SolveResult>()?;
    m.add_class::<PyModel>()?;
    m.add_function(wrap_pyfunction!(solve, m)?)?;
    m.add_function(wrap_pyfunction!(load_model, m)?)?;
    m.add_function(wrap_pyfunction!(methods, m)?)?;
    m.add_function(wrap_pyfunction!(score, m)?)?;
    m.add_function(wrap_pyfunction!(reallocate, m)?)?;
    m.add_function(wrap_pyfunction!(q_star, m)?)?;
    Ok(())
}

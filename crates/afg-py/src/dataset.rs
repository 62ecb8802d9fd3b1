//! Instances in and out of Python: reading and writing JSON Lines datasets, and the
//! generator with every knob of `afg gen`.

use std::path::PathBuf;

use afg_game::{Family, GeneratorKnobs, Instance};
use pyo3::prelude::*;

use crate::args::{FloatPair, Whole, WholePair};

use crate::{PyInstance, crate_error};

/// Reads a JSON Lines dataset (or one instance document): a list of instances.
#[pyfunction]
fn read_jsonl(path: PathBuf) -> PyResult<Vec<PyInstance>> {
    let instances = afg_game::io::read_instances(&path).map_err(crate_error)?;
    Ok(instances.into_iter().map(PyInstance::new_from).collect())
}

/// The named families of team games `generate(family=...)` draws, the committed ones
/// (`scarce`, `skills`) first.
#[pyfunction]
fn families() -> Vec<&'static str> {
    Family::ALL.iter().map(|f| f.name()).collect()
}

/// Writes instances as a JSON Lines dataset (atomically).
#[pyfunction]
fn write_jsonl(path: PathBuf, instances: Vec<PyRef<'_, PyInstance>>) -> PyResult<()> {
    let insts: Vec<Instance> = instances.iter().map(|i| (*i.inner).clone()).collect();
    afg_game::fs::write_atomic(&path, afg_game::io::dataset_to_jsonl(&insts).as_bytes())
        .map_err(crate_error)
}

/// Draws an instance from the paper's distribution (uniform positions, rewards in
/// [N/M, 2N/M], eps = max(2, N/M), beta = 1), with the generator's knobs;
/// `allow_void=True` draws GRAPE's game, where robots may join the void task;
/// `min_team=(lo, hi)`, `skills=S`, `skill_share=p` and `requires=(lo, hi)` draw the
/// team games (as `afg gen`'s flags of the same names); `family="clustered"` (one of
/// `afg.families()`) starts from a named family of team games instead, the knobs given
/// beside it overriding its values.
#[pyfunction]
#[pyo3(signature = (robots, tasks=Whole(5), seed=Whole(0), capacity_slack=None, eps=None, beta=None, rewards=None, allow_void=false, min_team=None, skills=None, skill_share=None, requires=None, family=None))]
// Python's keyword arguments, one per knob.
#[allow(clippy::too_many_arguments)]
fn generate(
    py: Python<'_>,
    robots: Whole,
    tasks: Whole,
    seed: Whole,
    capacity_slack: Option<f64>,
    eps: Option<f64>,
    beta: Option<f64>,
    rewards: Option<FloatPair>,
    allow_void: bool,
    min_team: Option<WholePair>,
    skills: Option<Whole>,
    skill_share: Option<f64>,
    requires: Option<WholePair>,
    family: Option<&str>,
) -> PyResult<PyInstance> {
    let knobs = GeneratorKnobs {
        capacity_slack,
        eps,
        beta,
        rewards: rewards.map(|FloatPair(lo, hi)| (lo, hi)),
        allow_void,
        min_team: min_team.map(|WholePair(lo, hi)| (lo, hi)),
        skills: skills.map(|s| s.count()).transpose()?,
        skill_share,
        requires: requires.map(|WholePair(lo, hi)| (lo, hi)),
        family: family
            .map(str::parse::<Family>)
            .transpose()
            .map_err(|e| crate::bad_input(format!("family: {e}")))?,
    };
    let inst = knobs
        .config(robots.count()?, tasks.count()?, seed.0)
        .and_then(|cfg| cfg.generate())
        .map_err(crate_error)?;
    let unstaffable: Vec<usize> = inst.unstaffable_tasks().iter().map(|j| j.index()).collect();
    crate::warn(py, afg_game::unstaffable_warning(&unstaffable))?;
    Ok(PyInstance::new_from(inst))
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(read_jsonl, m)?)?;
    m.add_function(wrap_pyfunction!(write_jsonl, m)?)?;
    m.add_function(wrap_pyfunction!(generate, m)?)?;
    m.add_function(wrap_pyfunction!(families, m)?)?;
    Ok(())
}

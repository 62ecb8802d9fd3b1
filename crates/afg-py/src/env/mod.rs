//! The sequential allocation MDP for the Gymnasium environments: one episode
//! ([`EnvCore`]) and K episodes stepped in one call ([`VecEnvCore`]). The MDP is
//! afg-learn's [`Env`]; this module keeps its assignment between Python calls.

use std::sync::Arc;

use afg_game::{Assignment, GeneratorKnobs, Instance, TaskId};
use afg_graph::{StateParts, Units};
use afg_learn::env::{Env, Shaping};
use numpy::ndarray::{Array1, Array2};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyArrayMethods};
use pyo3::prelude::*;
use rayon::prelude::*;

use crate::{PyInstance, bad_input};

mod episode;
use episode::{Episode, ObservationArrays};

/// One episode of the sequential MDP, driven by `afg.gym.AllocationEnv`.
#[pyclass(module = "afg")]
pub struct EnvCore {
    episode: Episode,
}

#[pymethods]
impl EnvCore {
    #[new]
    #[pyo3(signature = (instance, units="bounded", shaping="none", void_action=false))]
    fn py_new(
        instance: &PyInstance,
        units: &str,
        shaping: &str,
        void_action: bool,
    ) -> PyResult<Self> {
        let episode = Episode::new(
            instance.inner.clone(),
            crate::named::<Units>(units)?,
            crate::named::<Shaping>(shaping)?,
            void_action,
        )
        .map_err(crate::bad_input)?;
        Ok(EnvCore { episode })
    }

    /// Starts a new episode on `instance` (same units, shaping and actions).
    fn reset(&mut self, instance: &PyInstance) -> PyResult<()> {
        self.episode = self
            .episode
            .renew(instance.inner.clone())
            .map_err(crate::bad_input)?;
        Ok(())
    }

    /// The acting robot takes task `action`: `(reward, terminated)`.
    fn step(&mut self, py: Python<'_>, action: i64) -> PyResult<(f64, bool)> {
        let episode = &mut self.episode;
        py.detach(|| episode.step(action)).map_err(crate::bad_input)
    }

    /// `(robot_features (N, M), task_features (N, M), actor, action_mask (actions,))`.
    fn observation<'py>(&mut self, py: Python<'py>) -> ObservationArrays<'py> {
        let (n, m) = (
            self.episode.instance.num_robots(),
            self.episode.instance.num_tasks(),
        );
        let (mut nu, mut mu, mut mask) = (
            Array2::zeros((n, m)),
            Array2::zeros((n, m)),
            Array1::zeros(self.episode.actions()),
        );
        let actor = self.episode.observe_into(
            nu.as_slice_mut().expect("contiguous"),
            mu.as_slice_mut().expect("contiguous"),
            mask.as_slice_mut().expect("contiguous"),
        );
        (
            nu.into_pyarray(py),
            mu.into_pyarray(py),
            actor,
            mask.into_pyarray(py),
        )
    }

    /// Exact action values of the acting robot (-inf where masked).
    fn q_star<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        Ok(self.episode.q_star(py)?.into_pyarray(py))
    }

    /// The assignment so far (-1 for robots yet to act).
    fn tasks<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        self.episode.tasks().into_pyarray(py)
    }

    /// Welfare of the assignment so far.
    fn welfare(&self) -> f64 {
        self.episode.instance.welfare(self.episode.assignment())
    }

    /// The episode's instance.
    #[getter]
    fn instance(&self) -> PyInstance {
        PyInstance {
            inner: self.episode.instance.clone(),
        }
    }
}

/// Where a vector environment's instances come from: the generator and its knobs.
#[derive(Clone)]
struct InstanceSource {
    robots: usize,
    tasks: usize,
    knobs: GeneratorKnobs,
}

impl InstanceSource {
    fn instance(&self, seed: u64) -> Result<Instance, afg_game::GameError> {
        self.knobs.config(self.robots, self.tasks, seed)?.generate()
    }
}

type VecObservationArrays<'py> = (
    Bound<'py, PyArray3<f32>>,
    Bound<'py, PyArray3<f32>>,
    Bound<'py, PyArray1<i64>>,
    Bound<'py, PyArray2<i8>>,
);

/// A vector step's rewards and terminations.
type StepArrays<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<bool>>);

/// K episodes of the sequential MDP stepped in one call (spread over the cores with
/// rayon), driven by `afg.gym.AllocationVectorEnv`.
#[pyclass(module = "afg")]
pub struct VecEnvCore {
    episodes: Vec<Episode>,
    draw: InstanceSource,
    /// The stacked observation arrays, made once and overwritten by every
    /// `observations` call (a fresh half-megabyte per step cost more in page faults
    /// than the step itself at N = 1000).
    buffers: Option<Buffers>,
}

/// The arrays `VecEnvCore::observations` fills.
struct Buffers {
    nu: Py<PyArray3<f32>>,
    mu: Py<PyArray3<f32>>,
    actors: Py<PyArray1<i64>>,
    masks: Py<PyArray2<i8>>,
}

#[pymethods]
impl VecEnvCore {
    #[new]
    #[pyo3(signature = (num_envs, robots, tasks=5, capacity_slack=None, eps=None, beta=1.0, units="bounded", shaping="none", allow_void=false, min_team=None, skills=None, skill_share=None, requires=None))]
    #[allow(clippy::too_many_arguments)]
    fn py_new(
        num_envs: usize,
        robots: usize,
        tasks: usize,
        capacity_slack: Option<f64>,
        eps: Option<f64>,
        beta: f64,
        units: &str,
        shaping: &str,
        allow_void: bool,
        min_team: Option<(usize, usize)>,
        skills: Option<usize>,
        skill_share: Option<f64>,
        requires: Option<(usize, usize)>,
    ) -> PyResult<Self> {
        if num_envs == 0 {
            return Err(crate::bad_input("num_envs must be at least 1"));
        }
        let draw = InstanceSource {
            robots,
            tasks,
            knobs: GeneratorKnobs {
                capacity_slack,
                eps,
                beta: Some(beta),
                rewards: None,
                allow_void,
                min_team,
                skills,
                skill_share,
                requires,
                family: None,
            },
        };
        let first = Arc::new(draw.instance(0).map_err(crate::crate_error)?);
        let episode = Episode::new(
            first,
            crate::named::<Units>(units)?,
            crate::named::<Shaping>(shaping)?,
            allow_void,
        )
        .map_err(crate::bad_input)?;
        Ok(VecEnvCore {
            episodes: vec![episode; num_envs],
            draw,
            buffers: None,
        })
    }

    /// Starts new episodes: environment `indices[k]` on the instance drawn with
    /// `seeds[k]`.
    fn reset(&mut self, py: Python<'_>, indices: Vec<usize>, seeds: Vec<u64>) -> PyResult<()> {
        if indices.len() != seeds.len() || indices.iter().any(|&i| i >= self.episodes.len()) {
            return Err(crate::bad_input(
                "one seed per index, each index below num_envs",
            ));
        }
        let draw = self.draw.clone();
        let fresh = py
            .detach(|| {
                seeds
                    .iter()
                    .map(|&s| draw.instance(s))
                    .collect::<Result<Vec<_>, _>>()
            })
            .map_err(crate::crate_error)?;
        for (i, inst) in indices.into_iter().zip(fresh) {
            self.episodes[i] = self.episodes[i]
                .renew(Arc::new(inst))
                .map_err(crate::bad_input)?;
        }
        Ok(())
    }

    /// Every environment whose `skip` is false takes its action, and every one is
    /// observed, in one pass over the cores: `(rewards, terminated, robot_features,
    /// task_features, actors, action_masks)` (the observation arrays as
    /// [`VecEnvCore::observations`] gives them).
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        actions: Vec<i64>,
        skip: Vec<bool>,
    ) -> PyResult<(StepArrays<'py>, VecObservationArrays<'py>)> {
        let k = self.episodes.len();
        if actions.len() != k || skip.len() != k {
            return Err(crate::bad_input(format!(
                "expected {k} actions and {k} skip flags, got {} and {}",
                actions.len(),
                skip.len()
            )));
        }
        let (results, observed) = self.pass(py, Some((&actions, &skip)))?;
        let (rewards, done): (Vec<f64>, Vec<bool>) = results.into_iter().unzip();
        Ok(((rewards.into_pyarray(py), done.into_pyarray(py)), observed))
    }

    /// Stacked observations: `(robot_features (K, N, M), task_features (K, N, M),
    /// actors (K,), action_masks (K, actions))`. The same four arrays every call,
    /// overwritten: copy them to keep them past the next call.
    fn observations<'py>(&mut self, py: Python<'py>) -> PyResult<VecObservationArrays<'py>> {
        Ok(self.pass(py, None)?.1)
    }

    /// Environment `index`'s assignment so far.
    fn tasks<'py>(&self, py: Python<'py>, index: usize) -> PyResult<Bound<'py, PyArray1<i64>>> {
        Ok(self.episode(index)?.tasks().into_pyarray(py))
    }

    /// Environment `index`'s welfare so far.
    fn welfare(&self, index: usize) -> PyResult<f64> {
        let e = self.episode(index)?;
        Ok(e.instance.welfare(e.assignment()))
    }

    /// Environment `index`'s instance.
    fn instance(&self, index: usize) -> PyResult<PyInstance> {
        Ok(PyInstance {
            inner: self.episode(index)?.instance.clone(),
        })
    }
}

impl VecEnvCore {
    /// One pass over the cores: each environment takes its action (if `moves` are
    /// given and it is not skipped), then writes its observation into the buffers
    /// (made at the first pass). Returns each step's (reward, terminated).
    fn pass<'py>(
        &mut self,
        py: Python<'py>,
        moves: Option<(&[i64], &[bool])>,
    ) -> PyResult<(Vec<(f64, bool)>, VecObservationArrays<'py>)> {
        let (k, n, m) = (self.episodes.len(), self.draw.robots, self.draw.tasks);
        let actions = m + usize::from(self.draw.knobs.allow_void);
        let min_len = self.min_len();
        let buffers = self.buffers.get_or_insert_with(|| Buffers {
            nu: PyArray3::zeros(py, (k, n, m), false).unbind(),
            mu: PyArray3::zeros(py, (k, n, m), false).unbind(),
            actors: PyArray1::zeros(py, k, false).unbind(),
            masks: PyArray2::zeros(py, (k, actions), false).unbind(),
        });
        let (nu, mu) = (buffers.nu.bind(py).clone(), buffers.mu.bind(py).clone());
        let (actors, masks) = (
            buffers.actors.bind(py).clone(),
            buffers.masks.bind(py).clone(),
        );
        let results = {
            let (mut nu_w, mut mu_w) = (nu.readwrite(), mu.readwrite());
            let (mut actors_w, mut masks_w) = (actors.readwrite(), masks.readwrite());
            let nu_s = nu_w.as_slice_mut()?;
            let mu_s = mu_w.as_slice_mut()?;
            let actors_s = actors_w.as_slice_mut()?;
            let masks_s = masks_w.as_slice_mut()?;
            let episodes = &mut self.episodes;
            py.detach(|| {
                let nus = nu_s.par_chunks_mut(n * m);
                let mus = mu_s.par_chunks_mut(n * m);
                let rows = masks_s.par_chunks_mut(actions);
                episodes
                    .par_iter_mut()
                    .zip(nus)
                    .zip(mus)
                    .zip(rows)
                    .zip(actors_s.par_iter_mut())
                    .enumerate()
                    .with_min_len(min_len)
                    .map(|(i, ((((e, nu), mu), mask), actor))| {
                        let action = moves.and_then(|(a, skip)| (!skip[i]).then_some(a[i]));
                        let (moved, acting) = e
                            .step_and_observe(action, nu, mu, mask)
                            .map_err(|why| format!("environment {i}: {why}"))?;
                        *actor = acting as i64;
                        Ok(moved)
                    })
                    .collect::<Result<Vec<_>, String>>()
            })
            .map_err(crate::bad_input)?
        };
        Ok((results, (nu, mu, actors, masks)))
    }

    /// Sub-environments per rayon task: enough that a task does about 4 096 robots'
    /// work (a small N then stays on one thread, where splitting costs more than it
    /// saves).
    fn min_len(&self) -> usize {
        4096usize.div_ceil(self.draw.robots.max(1))
    }

    fn episode(&self, index: usize) -> PyResult<&Episode> {
        self.episodes
            .get(index)
            .ok_or_else(|| bad_input(format!("no environment {index}")))
    }
}

/// Adds the environment cores.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<EnvCore>()?;
    m.add_class::<VecEnvCore>()?;
    Ok(())
}

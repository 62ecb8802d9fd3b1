//! `afg.MissionEnv`: a mission driven by its robots as agents, the engine of the
//! PettingZoo environment `afg.pettingzoo.mission_v0`.

use afg_mission::{MissionEnv, Perception};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2, PyReadonlyArray1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::mission::PyMission;
use crate::value_error;

/// A mission whose living robots decide: at every decision epoch each picks a task it
/// knows is open (seen within `sensing`, else every open task; or heard of from a
/// robot within `comm_radius`) or keeps its own (action `num_tasks`). Observations are
/// each robot's own view; the reward is the team's value of the work done since the
/// last epoch.
#[pyclass(name = "MissionEnv", module = "afg", unsendable)]
pub(crate) struct PyMissionEnv {
    env: MissionEnv,
}

#[pymethods]
impl PyMissionEnv {
    #[new]
    #[pyo3(signature = (mission, sensing=None, comm_radius=0.25, decide_every=None))]
    fn new(
        mission: &PyMission,
        sensing: Option<f64>,
        comm_radius: f64,
        decide_every: Option<f64>,
    ) -> PyResult<Self> {
        let perception = Perception {
            sensing,
            comm_radius,
            decide_every,
        };
        let env = MissionEnv::new((*mission.inner).clone(), perception).map_err(value_error)?;
        Ok(PyMissionEnv { env })
    }

    /// Robots in the mission.
    #[getter]
    fn num_robots(&self) -> usize {
        self.env.num_robots()
    }

    /// Tasks in the mission (actions are 0..num_tasks, and num_tasks to keep one's own).
    #[getter]
    fn num_tasks(&self) -> usize {
        self.env.num_tasks()
    }

    /// Length of one robot's observation.
    #[getter]
    fn observation_len(&self) -> usize {
        self.env.observation_len()
    }

    /// The mission time now.
    #[getter]
    fn time(&self) -> f64 {
        self.env.time()
    }

    /// The robots to act now (none once the episode is over).
    fn agents(&self) -> Vec<usize> {
        self.env.agents()
    }

    /// Every robot's observation, (N, observation_len) float32 (rows of robots not
    /// acting are theirs all the same).
    fn observations<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f32>> {
        let (n, d) = (self.env.num_robots(), self.env.observation_len());
        let flat: Vec<f32> = (0..n).flat_map(|i| self.env.observe(i)).collect();
        Array2::from_shape_vec((n, d), flat)
            .expect("N rows of observation_len")
            .into_pyarray(py)
    }

    /// Every robot's action mask, (N, num_tasks + 1) int8.
    fn masks<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<i8>> {
        let (n, k) = (self.env.num_robots(), self.env.num_tasks());
        let flat: Vec<i8> = (0..n)
            .flat_map(|i| self.env.mask(i))
            .map(i8::from)
            .collect();
        Array2::from_shape_vec((n, k + 1), flat)
            .expect("N rows of num_tasks + 1")
            .into_pyarray(py)
    }

    /// The robots act — `actions[i]` for robot i, −1 for a robot not acting — and the
    /// mission runs to the next epoch. Returns (reward, failed robots, terminated,
    /// truncated).
    fn step(
        &mut self,
        actions: PyReadonlyArray1<'_, i64>,
    ) -> PyResult<(f64, Vec<usize>, bool, bool)> {
        let actions = actions.as_slice()?;
        if actions.len() != self.env.num_robots() {
            return Err(PyValueError::new_err(format!(
                "actions has {} entries for {} robots",
                actions.len(),
                self.env.num_robots()
            )));
        }
        let chosen: Vec<(usize, usize)> = (actions.iter().enumerate())
            .filter(|&(_, &a)| a >= 0)
            .map(|(i, &a)| (i, a as usize))
            .collect();
        let step = self.env.step(&chosen).map_err(value_error)?;
        Ok((step.reward, step.failed, step.terminated, step.truncated))
    }
}

/// Adds `MissionEnv`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyMissionEnv>()
}

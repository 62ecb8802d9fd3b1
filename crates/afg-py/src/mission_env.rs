//! `afg.MissionEnv`: a mission driven by its robots as agents, the engine of the
//! PettingZoo environment `afg.pettingzoo.mission_v0`.

use afg_mission::{MissionEnv, Perception};
use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray2, PyArray3, PyReadonlyArray1};
use std::sync::mpsc::{self, Sender};

use pyo3::prelude::*;

use crate::mission::PyMission;

/// A mission whose living robots decide: at every decision epoch each picks a task it
/// knows is open (seen within `sensing`, else every open task; or heard of from a
/// robot within `comm_radius`) or keeps its own (action `num_tasks`). Observations are
/// each robot's own view; the reward is the team's value of the work done since the
/// last epoch.
///
/// The simulator (which is not `Send`) lives on a thread of its own and every call is
/// a message to it, so the environment can be used from any Python thread (RLlib's
/// env runners, threaded vector environments).
#[pyclass(name = "MissionEnv", module = "afg")]
pub(crate) struct PyMissionEnv {
    jobs: Sender<Job>,
    num_robots: usize,
    num_tasks: usize,
    observation_len: usize,
}

/// A call for the simulator's thread.
type Job = Box<dyn FnOnce(&mut MissionEnv) + Send>;

impl PyMissionEnv {
    /// `f` on the simulator, on its thread; its answer.
    fn call<T: Send + 'static>(
        &self,
        py: Python<'_>,
        f: impl FnOnce(&mut MissionEnv) -> T + Send + 'static,
    ) -> PyResult<T> {
        let (tx, rx) = mpsc::channel();
        let job: Job = Box::new(move |env| {
            let _ = tx.send(f(env));
        });
        let lost = || crate::refused("the mission environment's thread has stopped");
        self.jobs.send(job).map_err(|_| lost())?;
        py.detach(move || rx.recv()).map_err(|_| lost())
    }
}

#[pymethods]
impl PyMissionEnv {
    #[new]
    #[pyo3(signature = (mission, sensing=None, comm_radius=0.25, decide_every=None, teams=false))]
    fn new(
        py: Python<'_>,
        mission: &PyMission,
        sensing: Option<f64>,
        comm_radius: f64,
        decide_every: Option<f64>,
        teams: bool,
    ) -> PyResult<Self> {
        let perception = Perception {
            sensing,
            comm_radius,
            decide_every,
            teams,
        };
        let mission = (*mission.inner).clone();
        let (jobs, inbox) = mpsc::channel::<Job>();
        let (ready, made) = mpsc::channel();
        std::thread::Builder::new()
            .name("afg-mission-env".into())
            .spawn(move || match MissionEnv::new(mission, perception) {
                Err(e) => {
                    let _ = ready.send(Err(e.to_string()));
                }
                Ok(mut env) => {
                    let sizes = (env.num_robots(), env.num_tasks(), env.observation_len());
                    let _ = ready.send(Ok(sizes));
                    for job in inbox {
                        job(&mut env);
                    }
                }
            })
            .map_err(|e| crate::refused(e.to_string()))?;
        let made = py.detach(move || made.recv());
        let (num_robots, num_tasks, observation_len) = made
            .map_err(|_| crate::refused("the mission environment's thread has stopped"))?
            .map_err(crate::bad_input)?;
        Ok(PyMissionEnv {
            jobs,
            num_robots,
            num_tasks,
            observation_len,
        })
    }

    /// Robots in the mission.
    #[getter]
    fn num_robots(&self) -> usize {
        self.num_robots
    }

    /// Tasks in the mission (actions are 0..num_tasks, and num_tasks to keep one's own).
    #[getter]
    fn num_tasks(&self) -> usize {
        self.num_tasks
    }

    /// Length of one robot's observation.
    #[getter]
    fn observation_len(&self) -> usize {
        self.observation_len
    }

    /// The mission time now.
    #[getter]
    fn time(&self, py: Python<'_>) -> PyResult<f64> {
        self.call(py, |env| env.time())
    }

    /// The robots to act now (none once the episode is over).
    fn agents(&self, py: Python<'_>) -> PyResult<Vec<usize>> {
        self.call(py, |env| env.agents())
    }

    /// Every robot's observation, (N, observation_len) float32 (rows of robots not
    /// acting are theirs all the same).
    fn observations<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let (n, d) = (self.num_robots, self.observation_len);
        let flat = self.call(py, move |env| {
            (0..n).flat_map(|i| env.observe(i)).collect::<Vec<f32>>()
        })?;
        let array = Array2::from_shape_vec((n, d), flat).expect("N rows of observation_len");
        Ok(array.into_pyarray(py))
    }

    /// The mission now as an image, (size, size, 3) uint8 RGB: the animation's drawing
    /// (robots coloured by task, rings where waiting for a team, tasks sized by the
    /// work left) without its text.
    #[pyo3(signature = (size=400))]
    fn render<'py>(&self, py: Python<'py>, size: usize) -> PyResult<Bound<'py, PyArray3<u8>>> {
        let pixels = self
            .call(py, move |env| {
                afg_eval::frame_image::frame_rgb(env.mission(), &env.frame(), size)
            })?
            .map_err(crate::crate_error)?;
        let array = Array3::from_shape_vec((size, size, 3), pixels).expect("size × size × 3 bytes");
        Ok(array.into_pyarray(py))
    }

    /// Every robot's action mask, (N, num_tasks + 1) int8.
    fn masks<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<i8>>> {
        let (n, k) = (self.num_robots, self.num_tasks);
        let flat = self.call(py, move |env| {
            (0..n)
                .flat_map(|i| env.mask(i))
                .map(i8::from)
                .collect::<Vec<i8>>()
        })?;
        let array = Array2::from_shape_vec((n, k + 1), flat).expect("N rows of num_tasks + 1");
        Ok(array.into_pyarray(py))
    }

    /// The robots act — `actions[i]` for robot i, −1 for a robot not acting — and the
    /// mission runs to the next epoch. Returns (reward, failed robots, terminated,
    /// truncated).
    fn step(
        &self,
        py: Python<'_>,
        actions: PyReadonlyArray1<'_, i64>,
    ) -> PyResult<(f64, Vec<usize>, bool, bool)> {
        let actions = actions.as_slice()?;
        if actions.len() != self.num_robots {
            return Err(crate::bad_input(format!(
                "actions has {} entries for {} robots",
                actions.len(),
                self.num_robots
            )));
        }
        let chosen: Vec<(usize, usize)> = (actions.iter().enumerate())
            .filter(|&(_, &a)| a >= 0)
            .map(|(i, &a)| (i, a as usize))
            .collect();
        let step = self
            .call(py, move |env| env.step(&chosen).map_err(|e| e.to_string()))?
            .map_err(crate::bad_input)?;
        Ok((step.reward, step.failed, step.terminated, step.truncated))
    }
}

/// Adds `MissionEnv`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyMissionEnv>()
}

//! One episode of the sequential MDP between Python calls: its state, a robot's
//! action, and its observation written into numpy's buffers.

use super::*;

/// One episode: the instance, and the MDP's state between calls (the assignment so far
/// and its features, the robots that have acted), the reward shaping, and whether the
/// actions end with M = the void task.
#[derive(Clone)]
pub(super) struct Episode {
    pub(super) instance: Arc<Instance>,
    /// Always `Some` between calls.
    pub(super) parts: Option<StateParts>,
    /// Robots that have acted (those that stayed out have no task in `parts`).
    pub(super) acted: usize,
    pub(super) shaping: Shaping,
    pub(super) void_action: bool,
}

impl Episode {
    /// A fresh episode.
    ///
    /// # Errors
    /// An instance that allows the void task for an environment without the void
    /// action, or with reward shaping (its completions would place the robots that
    /// stayed out).
    pub(super) fn new(
        instance: Arc<Instance>,
        units: Units,
        shaping: Shaping,
        void_action: bool,
    ) -> Result<Self, String> {
        if instance.allows_void() && !void_action {
            return Err("the instance allows the void task, but the environment has no action for it: make the environment with allow_void=True".into());
        }
        if instance.allows_void() && shaping != Shaping::None {
            return Err(format!(
                "reward shaping \"{}\" is not defined with the void task: use shaping=\"none\"",
                afg_game::Named::name(shaping)
            ));
        }
        let parts = Env::reset(&instance, units).into_parts();
        Ok(Episode {
            instance,
            parts: Some(parts),
            acted: 0,
            shaping,
            void_action,
        })
    }

    /// The same units, shaping and actions on another instance.
    pub(super) fn renew(&self, instance: Arc<Instance>) -> Result<Self, String> {
        Episode::new(instance, self.units(), self.shaping, self.void_action)
    }

    /// Actions: the M tasks, and the void where the environment has it.
    pub(super) fn actions(&self) -> usize {
        self.instance.num_tasks() + usize::from(self.void_action)
    }

    pub(super) fn parts(&self) -> &StateParts {
        self.parts
            .as_ref()
            .expect("an episode holds its state between calls")
    }

    pub(super) fn assignment(&self) -> &Assignment {
        self.parts().assignment()
    }

    pub(super) fn units(&self) -> Units {
        self.parts().units()
    }

    /// `f` on the MDP at this episode's state (O(N) to check it; nothing is rebuilt
    /// or copied).
    pub(super) fn with_env<T>(&mut self, f: impl FnOnce(&mut Env<'_>) -> T) -> T {
        let parts = self
            .parts
            .take()
            .expect("an episode holds its state between calls");
        let mut env = Env::from_parts_after(&self.instance, parts, self.acted)
            .expect("the episode's state is valid");
        let out = f(&mut env);
        self.acted = env.step_index();
        self.parts = Some(env.into_parts());
        out
    }

    /// The acting robot takes `action` (M: stays out): the (shaped) reward and whether
    /// it was the last.
    pub(super) fn step(&mut self, action: i64) -> Result<(f64, bool), String> {
        let (m, actions, shaping) = (self.instance.num_tasks(), self.actions(), self.shaping);
        self.with_env(|env| act(env, action, m, actions, shaping))
    }

    /// Writes the observation into `nu` and `mu` (N×M each) and `mask` (one per
    /// action): returns the actor (N once the episode is over).
    pub(super) fn observe_into(
        &mut self,
        nu: &mut [f32],
        mu: &mut [f32],
        mask: &mut [i8],
    ) -> usize {
        let (n, m) = (self.instance.num_robots(), self.instance.num_tasks());
        self.with_env(|env| write_observation(env, n, m, nu, mu, mask))
    }

    /// [`Episode::step`] with `action` (if given), then [`Episode::observe_into`], on
    /// one view of the state: `((reward, last), actor)`.
    pub(super) fn step_and_observe(
        &mut self,
        action: Option<i64>,
        nu: &mut [f32],
        mu: &mut [f32],
        mask: &mut [i8],
    ) -> Result<((f64, bool), usize), String> {
        let (n, m) = (self.instance.num_robots(), self.instance.num_tasks());
        let (actions, shaping) = (self.actions(), self.shaping);
        self.with_env(|env| {
            let moved = match action {
                Some(a) => act(env, a, m, actions, shaping)?,
                None => (0.0, false),
            };
            Ok((moved, write_observation(env, n, m, nu, mu, mask)))
        })
    }

    pub(super) fn tasks(&self) -> Vec<i64> {
        crate::task_indices(self.assignment())
    }

    /// Exact action values of the acting robot, one per action (-inf where masked).
    pub(super) fn q_star(&self, py: Python<'_>) -> PyResult<Vec<f64>> {
        let instance = PyInstance {
            inner: self.instance.clone(),
        };
        let mut values = crate::solve::q_star_of(py, &instance, self.tasks(), Some(self.acted))?;
        values.resize(self.actions(), f64::NEG_INFINITY);
        Ok(values)
    }
}

pub(super) type ObservationArrays<'py> = (
    Bound<'py, PyArray2<f32>>,
    Bound<'py, PyArray2<f32>>,
    usize,
    Bound<'py, PyArray1<i8>>,
);

/// The acting robot of `env` takes `action` of `actions` (M = `m`: stays out): the
/// (shaped) reward and whether it was the last.
fn act(
    env: &mut Env<'_>,
    action: i64,
    m: usize,
    actions: usize,
    shaping: Shaping,
) -> Result<(f64, bool), String> {
    let out_of_range = || format!("action {action} is not one of 0..{actions}");
    let action = usize::try_from(action).map_err(|_| out_of_range())?;
    if action >= actions {
        return Err(out_of_range());
    }
    if action == m {
        env.stay_out()
    } else {
        env.step_shaped(TaskId(action as u32), shaping)
    }
    .map_err(|e| e.to_string())
}

/// Writes `env`'s observation into `nu` and `mu` (N×M each) and `mask` (one per
/// action): returns the actor (`n` once the episode is over).
fn write_observation(
    env: &Env<'_>,
    n: usize,
    m: usize,
    nu: &mut [f32],
    mu: &mut [f32],
    mask: &mut [i8],
) -> usize {
    nu.fill(0.0);
    for (i, t) in env.state().assignment().tasks().iter().enumerate() {
        if let Some(j) = t {
            nu[i * m + j.index()] = 1.0;
        }
    }
    mu.copy_from_slice(env.state().mu_matrix());
    for (out, allowed) in mask.iter_mut().zip(env.action_mask()) {
        *out = i8::from(allowed);
    }
    if let Some(void) = mask.get_mut(m) {
        *void = i8::from(env.may_stay_out());
    }
    env.actor().map_or(n, |r| r.index())
}

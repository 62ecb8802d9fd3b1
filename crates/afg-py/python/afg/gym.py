"""The paper's sequential allocation MDP as Gymnasium environments.

Importing this module registers ``afg/Allocation-v0``::

    import gymnasium as gym
    import afg.gym
    env = gym.make("afg/Allocation-v0", robots=60, tasks=5)
    obs, info = env.reset(seed=0)

Robots act once each, in index order; the action is a task (``Discrete(M)``); the reward
is the change in welfare (optionally shaped), so an episode's return is its final
welfare. Observations are fixed-shape arrays in a ``Dict`` space, in the units the
project's networks read:

- ``robot_features`` (N, M) float32: one-hot of each robot's task (zeros before it acts);
- ``task_features`` (N, M) float32: the utility robot i would get in task j given the
  others' assignment, in units of beta, the value part capped (``units="bounded"``);
  a task without room shows -2;
- ``actor`` Discrete(N + 1): the robot to act (N once the episode is over);
- ``action_mask`` MultiBinary(M): the tasks the actor may take.

``allow_void=True`` plays GRAPE's game, where a robot may stay out of every coalition
(the void task): instances are drawn with the void allowed, the action space is
``Discrete(M + 1)`` with action M = stay out (reward 0), and ``action_mask`` has M + 1
entries (the last one false for an instance of the paper's game given in ``reset``).
Reward shaping is not defined there (``shaping`` must be ``"none"``).

**Teams** (``min_team``, ``skills``, ``skill_share``, ``requires``, as ``afg.generate``;
both environments, the vector one stacking each entry): instances are drawn with
thresholds and skills, the reward is the change in the team game's welfare (a coalition earns only once its team is
complete), and the observation has two more entries —

- ``team`` (M, 3 + S) float32: each task's threshold over N, its members so far over
  its threshold, whether its team is complete (threshold and skills), and per skill the
  share of its requirement its members do not hold yet (0 where it needs none);
- ``skills`` (N, S) float32: each robot's amount of each skill —

and ``action_mask`` also forbids a task no team can staff (a threshold above N, or a
skill the robots lack together), unless that would leave the actor no action.

``info["action_mask"]`` is given at every step and ``action_masks()`` for maskable
agents. On the last step ``info`` holds ``tasks``, ``welfare``, ``opt_welfare`` and
``percent_of_opt``. ``reset(options={"instance": inst})`` plays a given instance;
``options={"oracle": True}`` adds ``info["q_star"]``, the exact action values of every
action (-inf where masked), from then on.
"""

from __future__ import annotations

from typing import Any, Dict, Optional, Tuple

import gymnasium
import numpy as np
from gymnasium import spaces
from gymnasium.vector import VectorEnv
from gymnasium.vector.utils import batch_space

from . import EnvCore, Instance, InvalidInputError, VecEnvCore, generate, score

__all__ = ["AllocationEnv", "AllocationVectorEnv"]

_SEED_BOUND = 2**63


def _observation_space(robots: int, tasks: int, actions: int, skills: Optional[int] = None) -> spaces.Dict:
    features = spaces.Box(-np.inf, np.inf, shape=(robots, tasks), dtype=np.float32)
    entries: Dict[str, spaces.Space] = {
        "robot_features": spaces.Box(0.0, 1.0, shape=(robots, tasks), dtype=np.float32),
        "task_features": features,
        "actor": spaces.Discrete(robots + 1),
        "action_mask": spaces.MultiBinary(actions),
    }
    if skills is not None:
        entries["team"] = spaces.Box(-np.inf, np.inf, shape=(tasks, 3 + skills), dtype=np.float32)
        entries["skills"] = spaces.Box(0.0, np.inf, shape=(robots, skills), dtype=np.float32)
    return spaces.Dict(entries)


def _team_view(instance: Instance, tasks: np.ndarray) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The ``team`` and ``skills`` entries for an assignment so far (``tasks``: each
    robot's task, -1 for none yet), and which tasks some team could staff."""
    n = instance.num_robots
    k = instance.min_team.astype(np.float64)
    skills, requires = instance.skills.astype(np.float64), instance.requires.astype(np.float64)
    members = np.zeros(len(k))
    held = np.zeros_like(requires)
    for robot, task in enumerate(tasks):
        if task >= 0:
            members[task] += 1
            held[task] += skills[robot]
    with np.errstate(divide="ignore", invalid="ignore"):
        missing = np.where(requires > 0, np.maximum(requires - held, 0.0) / requires, 0.0)
    complete = (members >= k) & (held >= requires).all(axis=1)
    team = np.column_stack([k / n, members / k, complete, missing]).astype(np.float32)
    staffable = (k <= n) & (skills.sum(axis=0) >= requires).all(axis=1)
    return team, skills.astype(np.float32), staffable


def _staffable_only(mask: np.ndarray, staffable: np.ndarray) -> np.ndarray:
    """``mask`` without the tasks no team can staff, unless that leaves nothing."""
    allowed = mask.copy()
    allowed[: len(staffable)] &= staffable.astype(mask.dtype)
    return allowed if allowed.any() else mask


def _staffable_masks(masks: np.ndarray, views: list) -> np.ndarray:
    """Each row of ``masks`` without the tasks its ``_team_view`` says no team can staff."""
    return np.stack([_staffable_only(mask, staffable) for mask, (_, _, staffable) in zip(masks, views)])


def _teams_drawn(min_team, skills, skill_share, requires) -> Dict[str, Any]:
    """The team knobs given (those left out are not passed to the generator)."""
    teams = dict(min_team=min_team, skills=skills, skill_share=skill_share, requires=requires)
    return {key: value for key, value in teams.items() if value is not None}


def _final_info(instance: Instance, tasks: np.ndarray) -> Dict[str, Any]:
    scored = score(instance, tasks)
    return {
        "tasks": tasks,
        "welfare": scored.welfare,
        "opt_welfare": scored.opt_welfare,
        "percent_of_opt": scored.percent_of_opt,
    }


class AllocationEnv(gymnasium.Env):
    """One episode per instance of N robots and M tasks (see the module docs)."""

    metadata = {"render_modes": []}

    def __init__(
        self,
        robots: int = 20,
        tasks: int = 5,
        capacity_slack: Optional[float] = None,
        eps: Optional[float] = None,
        beta: float = 1.0,
        units: str = "bounded",
        shaping: str = "none",
        allow_void: bool = False,
        min_team: Optional[Tuple[int, int]] = None,
        skills: Optional[int] = None,
        skill_share: Optional[float] = None,
        requires: Optional[Tuple[int, int]] = None,
    ) -> None:
        self.robots, self.tasks = int(robots), int(tasks)
        self.allow_void = bool(allow_void)
        actions = self.tasks + int(self.allow_void)
        teams = _teams_drawn(min_team, skills, skill_share, requires)
        self._teams = bool(teams)
        self._draw = dict(capacity_slack=capacity_slack, eps=eps, beta=beta, allow_void=self.allow_void, **teams)
        self._units, self._shaping = units, shaping
        first = generate(self.robots, self.tasks, 0, **self._draw)
        self._skills = first.skills.shape[1] if self._teams else None
        self.observation_space = _observation_space(self.robots, self.tasks, actions, self._skills)
        self.action_space = spaces.Discrete(actions)
        self._core = EnvCore(first, units, shaping, void_action=self.allow_void)
        self._oracle = False

    def _observe(self) -> Tuple[Dict[str, Any], Dict[str, Any]]:
        nu, mu, actor, mask = self._core.observation()
        obs = {"robot_features": nu, "task_features": mu, "actor": actor, "action_mask": mask}
        if self._teams:
            team, skills, staffable = _team_view(self._core.instance, self._core.tasks())
            obs["team"], obs["skills"] = team, skills
            obs["action_mask"] = mask = _staffable_only(mask, staffable)
        info: Dict[str, Any] = {"action_mask": mask.astype(bool)}
        if self._oracle and actor < self.robots:
            info["q_star"] = self._core.q_star()
        return obs, info

    def reset(
        self, *, seed: Optional[int] = None, options: Optional[Dict[str, Any]] = None
    ) -> Tuple[Dict[str, Any], Dict[str, Any]]:
        super().reset(seed=seed)
        options = options or {}
        self._oracle = bool(options.get("oracle", False))
        instance = options.get("instance")
        if instance is None:
            draw = int(self.np_random.integers(_SEED_BOUND))
            instance = generate(self.robots, self.tasks, draw, **self._draw)
        elif (instance.num_robots, instance.num_tasks) != (self.robots, self.tasks):
            raise InvalidInputError(
                f"the instance has {instance.num_robots} robots and {instance.num_tasks} "
                f"tasks, the environment's spaces {self.robots} and {self.tasks}"
            )
        elif self._teams and instance.skills.shape[1] != self._skills:
            raise InvalidInputError(
                f"the instance has {instance.skills.shape[1]} skills, the environment's "
                f"spaces {self._skills}"
            )
        self._core.reset(instance)
        return self._observe()

    def step(self, action: Any) -> Tuple[Dict[str, Any], float, bool, bool, Dict[str, Any]]:
        reward, terminated = self._core.step(int(action))
        obs, info = self._observe()
        if terminated:
            info.update(_final_info(self._core.instance, self._core.tasks()))
        return obs, float(reward), bool(terminated), False, info

    def action_masks(self) -> np.ndarray:
        """The acting robot's allowed actions, as booleans (for maskable agents)."""
        mask = self._core.observation()[3]
        if self._teams:
            mask = _staffable_only(mask, _team_view(self._core.instance, self._core.tasks())[2])
        return mask.astype(bool)


class AllocationVectorEnv(VectorEnv):
    """K episodes stepped together in Rust, with stacked observations.

    Finished sub-environments reset on the following ``step`` (Gymnasium's next-step
    autoreset): that step ignores their action and returns reward 0. With
    ``copy=False`` the observation arrays are the same ones every step, overwritten by
    the next (as Gymnasium's ``SyncVectorEnv(copy=False)``): faster, for a loop that
    copies them into its own buffer anyway.
    """

    metadata = {"autoreset_mode": gymnasium.vector.AutoresetMode.NEXT_STEP}

    def __init__(
        self,
        num_envs: int = 4,
        robots: int = 20,
        tasks: int = 5,
        capacity_slack: Optional[float] = None,
        eps: Optional[float] = None,
        beta: float = 1.0,
        units: str = "bounded",
        shaping: str = "none",
        allow_void: bool = False,
        min_team: Optional[Tuple[int, int]] = None,
        skills: Optional[int] = None,
        skill_share: Optional[float] = None,
        requires: Optional[Tuple[int, int]] = None,
        copy: bool = True,
    ) -> None:
        self.num_envs, self.robots, self.tasks = int(num_envs), int(robots), int(tasks)
        self.copy = bool(copy)
        self.allow_void = bool(allow_void)
        actions = self.tasks + int(self.allow_void)
        teams = _teams_drawn(min_team, skills, skill_share, requires)
        self._core = VecEnvCore(
            self.num_envs, self.robots, self.tasks, capacity_slack, eps, beta, units, shaping,
            self.allow_void, **teams,
        )
        self._skills = self._core.instance(0).skills.shape[1] if teams else None
        self.single_observation_space = _observation_space(self.robots, self.tasks, actions, self._skills)
        self.single_action_space = spaces.Discrete(actions)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self._autoreset = np.zeros(self.num_envs, dtype=bool)

    def _draw(self, count: int) -> list:
        return [int(s) for s in self.np_random.integers(_SEED_BOUND, size=count)]

    def _observe(self, arrays: Optional[Tuple[np.ndarray, ...]] = None) -> Tuple[Dict[str, Any], Dict[str, Any]]:
        nu, mu, actors, masks = self._core.observations() if arrays is None else arrays
        if self.copy:
            # One block for both feature arrays: two large copies freed together would
            # let the C allocator return them to the system and fault them back in at
            # every step (several times the step's cost at N = 1000).
            block = np.empty((2,) + nu.shape, dtype=np.float32)
            block[0], block[1] = nu, mu
            nu, mu, actors, masks = block[0], block[1], actors.copy(), masks.copy()
        obs = {"robot_features": nu, "task_features": mu, "actor": actors, "action_mask": masks}
        if self._skills is not None:
            views = self._team_views()
            obs["team"] = np.stack([team for team, _, _ in views])
            obs["skills"] = np.stack([skills for _, skills, _ in views])
            obs["action_mask"] = masks = _staffable_masks(masks, views)
        return obs, {"action_mask": masks.astype(bool)}

    def _team_views(self) -> list:
        """Each sub-environment's ``_team_view``."""
        return [_team_view(self._core.instance(i), self._core.tasks(i)) for i in range(self.num_envs)]

    def reset(
        self, *, seed: Optional[int] = None, options: Optional[Dict[str, Any]] = None
    ) -> Tuple[Dict[str, Any], Dict[str, Any]]:
        super().reset(seed=seed)
        self._core.reset(list(range(self.num_envs)), self._draw(self.num_envs))
        self._autoreset[:] = False
        return self._observe()

    def step(self, actions: Any):
        actions = np.asarray(actions, dtype=np.int64).reshape(self.num_envs)
        skip = self._autoreset.copy()
        if skip.any():
            indices = [int(i) for i in np.flatnonzero(skip)]
            self._core.reset(indices, self._draw(len(indices)))
        (rewards, terminated), arrays = self._core.step(actions.tolist(), skip.tolist())
        obs, info = self._observe(arrays)
        if terminated.any():
            finals = [
                _final_info(self._core.instance(i), self._core.tasks(i)) if done else None
                for i, done in enumerate(terminated)
            ]
            info["welfare"] = np.array([f["welfare"] if f else np.nan for f in finals])
            info["percent_of_opt"] = np.array(
                [f["percent_of_opt"] if f and f["percent_of_opt"] is not None else np.nan for f in finals]
            )
            info["_welfare"] = info["_percent_of_opt"] = terminated.copy()
        self._autoreset = terminated.copy()
        truncated = np.zeros(self.num_envs, dtype=bool)
        return obs, rewards, terminated, truncated, info

    def action_masks(self) -> np.ndarray:
        """Each sub-environment's allowed actions, shape (K, actions), as booleans."""
        masks = self._core.observations()[3]
        if self._skills is not None:
            masks = _staffable_masks(masks, self._team_views())
        return masks.astype(bool)


def _register() -> None:
    if "afg/Allocation-v0" not in gymnasium.registry:
        gymnasium.register(
            id="afg/Allocation-v0",
            entry_point="afg.gym:AllocationEnv",
            vector_entry_point="afg.gym:AllocationVectorEnv",
        )


_register()

"""A mission over time as a PettingZoo Parallel environment: every robot an agent.

Each episode is a mission drawn by ``afg.Mission.generate`` (a new one per reset,
seeded by ``reset(seed=…)``). At every decision epoch — a task appears or is done, a
robot fails, and every ``decide_every`` time units if given — every robot still in the
episode picks, at once, a task it knows is open or keeps its own; the mission then
runs (exact, event-driven time) to the next epoch:

- **action**: ``Discrete(K + 1)`` for the mission's K tasks: ``k < K`` heads for task k,
  ``K`` keeps the robot's own task (or idles). An action the mask forbids keeps its own.
- **observation** (``Dict``): ``observation`` float32 of length ``5 + 9 K`` — the
  robot's own view: its x, y and one-hot state (idle, travelling, working), then per
  task: known and open, dx, dy, distance, reward over the mission's largest, eps, share
  of the work left, share of its neighbours heading there, whether it is its own task
  (all zero for a task it does not know is open); ``action_mask`` int8 of length
  ``K + 1``.
- **teams** (when ``min_team`` or ``skills`` is given): the observation grows to
  ``5 + S + K (13 + S)`` for S skills — the robot's own skills after its state, and
  after each task's nine: its threshold over N, the robots present over the
  threshold, those heading there or present over the threshold, whether the present
  team is complete, and per skill the share of its requirement that those robots do
  not hold — and a task that no team of the living robots can staff (a threshold
  above them, a skill they lack together) is masked.
- **what a robot knows**: with ``sensing=None`` every open task; with ``sensing=s`` the
  open tasks within s of it and those a robot within ``comm_radius`` knew at the last
  epoch (news spreads one hop per epoch). ``comm_radius`` also bounds the neighbours
  whose heading it sees.
- **reward**: a team reward: every agent receives ``Σ r_j`` times the work done on each
  task since the last epoch, so an episode's return is the value of all the work done.
- **end**: a robot that fails is terminated and leaves; when every task is done all
  are terminated, at the horizon all are truncated, and after ``max_cycles`` steps (if
  given) all are truncated. ``infos`` are empty dicts.
- **failed robots kept** (``keep_failed=True``): as SMAC does with dead units, a robot
  that fails stays an agent until the episode ends, with an all-zero observation and
  only "keep" allowed (its action changes nothing), so that the set of agents never
  changes within an episode (what SuperSuit's vector wrappers and parameter sharing
  need).
- **global state** for centralised critics (MAPPO, QMIX): ``state()`` is every robot's
  observation, concatenated in index order (zeros for a robot that failed), as
  PettingZoo's MPE environments do; ``state_space`` is its ``Box``.
- **render_mode**: ``None`` or ``"rgb_array"``: ``render()`` then returns the mission
  now as a (``render_size``, ``render_size``, 3) uint8 image (default 400), the drawing
  of ``afg mission run --animate`` without its text — robots coloured by task (grey:
  none, a red cross: failed, a black ring: waiting for the rest of its team), tasks as
  squares sized by the work left.

Keyword arguments: ``robots``, ``tasks`` and ``preset`` ("static", "waves", "poisson",
"attrition"), every knob of ``afg.Mission.generate`` (``workload``, ``speed``,
``arena``, ``horizon``, ``waves``, ``interval``, ``rate``, ``fail_share``,
``capacity_slack``, ``allow_void``, ``min_team``, ``skills``, ``skill_share``,
``requires``), ``sensing``, ``comm_radius``, ``decide_every``,
``max_cycles``, ``keep_failed``, ``render_mode`` and ``render_size``.
"""

from __future__ import annotations

from typing import Any, Dict, List, Optional, Tuple

import numpy as np
from gymnasium import spaces
from pettingzoo import AECEnv, ParallelEnv
from pettingzoo.utils import parallel_to_aec, wrappers

from .. import Mission, MissionEnv, RefusedError
from ._checks import check_max_cycles, check_render_mode

__all__ = ["env", "parallel_env", "raw_env"]


def parallel_env(**kwargs: Any) -> "MissionParallelEnv":
    """The Parallel environment."""
    return MissionParallelEnv(**kwargs)


def raw_env(**kwargs: Any) -> AECEnv:
    """The same environment as an AEC one (robots in index order)."""
    return parallel_to_aec(parallel_env(**kwargs))


def env(**kwargs: Any) -> AECEnv:
    """The AEC environment with PettingZoo's usual checking wrappers."""
    wrapped: AECEnv = raw_env(**kwargs)
    wrapped = wrappers.AssertOutOfBoundsWrapper(wrapped)
    return wrappers.OrderEnforcingWrapper(wrapped)


class MissionParallelEnv(ParallelEnv):
    """Robots as agents of a mission (see the module docs)."""

    metadata = {"render_modes": ["rgb_array"], "name": "mission_v0", "is_parallelizable": True}

    def __init__(
        self,
        robots: int = 20,
        tasks: int = 8,
        preset: str = "waves",
        sensing: Optional[float] = None,
        comm_radius: float = 0.25,
        decide_every: Optional[float] = None,
        max_cycles: Optional[int] = None,
        keep_failed: bool = False,
        render_mode: Optional[str] = None,
        render_size: int = 400,
        **knobs: Any,
    ) -> None:
        check_render_mode(render_mode, self.metadata)
        self.render_size = render_size
        self.max_cycles = check_max_cycles(max_cycles)
        self.keep_failed = keep_failed
        self._draw = lambda seed: Mission.generate(preset, robots, tasks, seed=seed, **knobs)
        teams = knobs.get("min_team") is not None or knobs.get("skills") is not None
        self._perception = dict(
            sensing=sensing, comm_radius=comm_radius, decide_every=decide_every, teams=teams
        )
        # Check every knob now: a bad one raises here, not at the first reset.
        length = MissionEnv(self._draw(0), **self._perception).observation_len
        self.possible_agents = [f"robot_{i}" for i in range(robots)]
        self._index = {a: i for i, a in enumerate(self.possible_agents)}
        observation = spaces.Dict(
            {
                "observation": spaces.Box(-np.inf, np.inf, shape=(length,), dtype=np.float32),
                "action_mask": spaces.Box(0, 1, shape=(tasks + 1,), dtype=np.int8),
            }
        )
        self._observation_spaces = {a: observation for a in self.possible_agents}
        self._action_spaces = {a: spaces.Discrete(tasks + 1) for a in self.possible_agents}
        self.state_space = spaces.Box(-np.inf, np.inf, shape=(robots * length,), dtype=np.float32)
        self._rng = np.random.default_rng()
        self._env: Optional[MissionEnv] = None
        self._failed: set = set()
        self._cycles = 0
        self.agents: List[str] = []
        self.render_mode = render_mode

    def observation_space(self, agent: str) -> spaces.Space:
        return self._observation_spaces[agent]

    def action_space(self, agent: str) -> spaces.Space:
        return self._action_spaces[agent]

    def _views(self) -> Tuple[np.ndarray, np.ndarray]:
        """Every robot's observation and mask; a failed robot's all zero, "keep" only."""
        assert self._env is not None
        obs, masks = self._env.observations(), self._env.masks()
        for i in self._failed:
            obs[i] = 0.0
            masks[i] = 0
            masks[i, -1] = 1
        return obs, masks

    def _observe(self, agents: List[str]) -> Dict[str, Dict[str, np.ndarray]]:
        obs, masks = self._views()
        return {
            a: {"observation": obs[self._index[a]], "action_mask": masks[self._index[a]]}
            for a in agents
        }

    def render(self) -> Optional[np.ndarray]:
        """The mission now as an (H, W, 3) uint8 image with ``render_mode="rgb_array"``;
        None without a render mode."""
        if self.render_mode is None:
            return None
        if self._env is None:
            raise RefusedError("call reset() before render()")
        return self._env.render(self.render_size)

    def state(self) -> np.ndarray:
        """The global state: every robot's observation, concatenated in index order."""
        if self._env is None:
            raise RefusedError("call reset() before state()")
        return self._views()[0].reshape(-1)

    def reset(
        self, seed: Optional[int] = None, options: Optional[Dict[str, Any]] = None
    ) -> Tuple[Dict[str, Any], Dict[str, Dict[str, Any]]]:
        if seed is not None:
            self._rng = np.random.default_rng(seed)
        mission = self._draw(int(self._rng.integers(2**63)))
        self._env = MissionEnv(mission, **self._perception)
        self._failed, self._cycles = set(), 0
        self.agents = [self.possible_agents[i] for i in self._env.agents()]
        return self._observe(self.agents), {a: {} for a in self.agents}

    def step(self, actions: Dict[str, Any]) -> Tuple[
        Dict[str, Any], Dict[str, float], Dict[str, bool], Dict[str, bool], Dict[str, Dict[str, Any]]
    ]:
        if self._env is None:
            raise RefusedError("call reset() before step()")
        chosen = np.full(len(self.possible_agents), -1, dtype=np.int64)
        for agent, action in actions.items():
            if agent in self.agents and self._index[agent] not in self._failed:
                chosen[self._index[agent]] = int(action)
        acting = self.agents
        reward, failed, terminated, truncated = self._env.step(chosen)
        self._cycles += 1
        truncated = truncated or (self.max_cycles is not None and self._cycles >= self.max_cycles)
        ended = terminated or truncated
        if self.keep_failed:
            self._failed.update(failed)
            gone = set()
            self.agents = [] if ended else acting
        else:
            gone = {self.possible_agents[i] for i in failed}
            self.agents = [] if ended else [self.possible_agents[i] for i in self._env.agents()]
        observations = self._observe(acting)
        rewards = {a: reward for a in acting}
        terminations = {a: terminated or a in gone for a in acting}
        truncations = {a: truncated and not terminated and a not in gone for a in acting}
        return observations, rewards, terminations, truncations, {a: {} for a in acting}

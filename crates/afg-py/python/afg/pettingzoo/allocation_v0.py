"""The paper's sequential allocation MDP as a PettingZoo AEC environment.

Each robot is an agent (``robot_0`` … ``robot_{N-1}``); they act once each, in index
order, exactly as in ``afg/Allocation-v0`` (the same engine underneath, step for step):

- **action**: ``Discrete(M)``, the task the acting robot joins (``Discrete(M + 1)`` with
  ``allow_void=True``, action M = stay out);
- **observation** (``Dict``): ``observation`` (M,) float32 — the agent's own view, the
  utility it would get in each task given the others' assignment (the row of
  ``afg/Allocation-v0``'s ``task_features``); ``action_mask`` (actions,) int8 — the tasks
  the agent may take when it is its turn, all zeros otherwise;
- **reward**: a team reward: every agent receives each step's change in welfare, so each
  agent's return is the final welfare;
- the episode ends for every agent after the last robot acts; ``infos`` then hold
  ``tasks``, ``welfare``, ``opt_welfare`` and ``percent_of_opt``;
- **global state** for centralised critics: ``state()`` is every robot's observation
  concatenated in index order (the whole (N, M) utility table, flattened), as
  PettingZoo's MPE environments do; ``state_space`` is its ``Box``.

With the team games' knobs (``min_team``, ``skills``, ``skill_share``, ``requires``)
the observation also holds ``team`` (M, 3 + S) — every task's threshold and team so far,
as ``afg/Allocation-v0``'s entry of that name — and ``skills`` (S,), the agent's own.

Keyword arguments as ``afg/Allocation-v0``'s: ``robots``, ``tasks``,
``capacity_slack``, ``eps``, ``beta``, ``units``, ``allow_void``, ``min_team``,
``skills``, ``skill_share``, ``requires``; and PettingZoo's
``max_cycles`` (every robot acts once, so any limit ≥ 1 is never reached) and
``render_mode`` (``None`` only).
"""

from __future__ import annotations

from typing import Any, Dict, Optional, Tuple

import numpy as np
from gymnasium import spaces
from pettingzoo import AECEnv
from pettingzoo.utils import wrappers

from .._errors import RefusedError
from ..gym import AllocationEnv
from ._checks import check_max_cycles, check_render_mode

__all__ = ["env", "raw_env"]


def env(**kwargs: Any) -> AECEnv:
    """The environment with PettingZoo's usual checking wrappers."""
    wrapped: AECEnv = raw_env(**kwargs)
    wrapped = wrappers.AssertOutOfBoundsWrapper(wrapped)
    return wrappers.OrderEnforcingWrapper(wrapped)


class raw_env(AECEnv):  # noqa: N801 (PettingZoo's name)
    """Robots as agents of the sequential MDP (see the module docs)."""

    metadata = {"render_modes": [], "name": "allocation_v0", "is_parallelizable": False}

    def __init__(
        self,
        robots: int = 20,
        tasks: int = 5,
        capacity_slack: Optional[float] = None,
        eps: Optional[float] = None,
        beta: float = 1.0,
        units: str = "bounded",
        allow_void: bool = False,
        min_team: Optional[Tuple[int, int]] = None,
        skills: Optional[int] = None,
        skill_share: Optional[float] = None,
        requires: Optional[Tuple[int, int]] = None,
        max_cycles: Optional[int] = None,
        render_mode: Optional[str] = None,
    ) -> None:
        super().__init__()
        check_render_mode(render_mode, self.metadata)
        self.max_cycles = check_max_cycles(max_cycles)
        self.render_mode = render_mode
        self._game = AllocationEnv(
            robots=robots, tasks=tasks, capacity_slack=capacity_slack, eps=eps, beta=beta,
            units=units, allow_void=allow_void, min_team=min_team, skills=skills,
            skill_share=skill_share, requires=requires,
        )
        self.possible_agents = [f"robot_{i}" for i in range(robots)]
        self._index = {a: i for i, a in enumerate(self.possible_agents)}
        actions = int(self._game.action_space.n)
        entries: Dict[str, spaces.Space] = {
            "observation": spaces.Box(-np.inf, np.inf, shape=(tasks,), dtype=np.float32),
            "action_mask": spaces.Box(0, 1, shape=(actions,), dtype=np.int8),
        }
        game_space = self._game.observation_space
        self._teams = "team" in game_space.spaces
        if self._teams:
            entries["team"] = game_space["team"]
            s = game_space["skills"].shape[1]
            entries["skills"] = spaces.Box(0.0, np.inf, shape=(s,), dtype=np.float32)
        self._observation_space = spaces.Dict(entries)
        self._action_space = spaces.Discrete(actions)
        self.state_space = spaces.Box(-np.inf, np.inf, shape=(robots * tasks,), dtype=np.float32)
        self._obs: Dict[str, Any] = {}

    def observation_space(self, agent: str) -> spaces.Space:
        return self._observation_space

    def action_space(self, agent: str) -> spaces.Space:
        return self._action_space

    def reset(self, seed: Optional[int] = None, options: Optional[Dict[str, Any]] = None) -> None:
        self._obs, _ = self._game.reset(seed=seed, options=options)
        self.agents = self.possible_agents[:]
        self.rewards = {a: 0.0 for a in self.agents}
        self._cumulative_rewards = {a: 0.0 for a in self.agents}
        self.terminations = {a: False for a in self.agents}
        self.truncations = {a: False for a in self.agents}
        self.infos = {a: {} for a in self.agents}
        self.agent_selection = self.agents[0]

    def observe(self, agent: str) -> Dict[str, np.ndarray]:
        i = self._index[agent]
        acting = int(self._obs["actor"]) == i
        mask = self._obs["action_mask"] if acting else np.zeros(self._action_space.n)
        seen = {
            "observation": np.array(self._obs["task_features"][i], dtype=np.float32),
            "action_mask": np.asarray(mask, dtype=np.int8),
        }
        if self._teams:
            seen["team"] = np.array(self._obs["team"], dtype=np.float32)
            seen["skills"] = np.array(self._obs["skills"][i], dtype=np.float32)
        return seen

    def state(self) -> np.ndarray:
        """The global state: every robot's observation, concatenated in index order."""
        if not self._obs:
            raise RefusedError("call reset() before state()")
        return np.asarray(self._obs["task_features"], dtype=np.float32).reshape(-1)

    def step(self, action: Optional[int]) -> None:
        agent = self.agent_selection
        if self.terminations[agent] or self.truncations[agent]:
            self._was_dead_step(action)
            return
        self._cumulative_rewards[agent] = 0.0
        self._obs, reward, done, _, info = self._game.step(int(action))
        for a in self.agents:
            self.rewards[a] = float(reward)
        if done:
            for a in self.agents:
                self.terminations[a] = True
                self.infos[a] = dict(info)
        i = self._index[agent]
        self.agent_selection = self.agents[(i + 1) % len(self.agents)]
        self._accumulate_rewards()

    def render(self) -> None:
        return None

    def close(self) -> None:
        return None

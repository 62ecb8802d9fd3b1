"""The PettingZoo AEC environment: PettingZoo's own API and seed tests, and step for
step the same episode as afg/Allocation-v0."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

pytest.importorskip("pettingzoo")
from pettingzoo.test import api_test, seed_test  # noqa: E402

import afg.gym  # noqa: E402,F401
from afg.pettingzoo import allocation_v0  # noqa: E402


def test_pettingzoo_api_and_seed_tests_pass() -> None:
    api_test(allocation_v0.env(robots=8, tasks=3), num_cycles=20)
    seed_test(lambda: allocation_v0.env(robots=8, tasks=3), num_cycles=20)
    api_test(allocation_v0.env(robots=6, tasks=2, allow_void=True), num_cycles=20)


def test_the_aec_environment_is_the_gymnasium_one_step_by_step() -> None:
    rng = np.random.default_rng(0)
    aec = allocation_v0.env(robots=10, tasks=3)
    single = gym.make("afg/Allocation-v0", robots=10, tasks=3)
    aec.reset(seed=5)
    obs, info = single.reset(seed=5)
    returns = {}
    for t, agent in enumerate(aec.agent_iter()):
        observation, reward, terminated, truncated, agent_info = aec.last()
        if terminated:
            returns[agent] = returns.get(agent, 0.0) + reward
            aec.step(None)
            continue
        assert agent == f"robot_{t}" and obs["actor"] == t
        assert (observation["observation"] == obs["task_features"][t]).all()
        assert (observation["action_mask"] == obs["action_mask"]).all()
        returns[agent] = returns.get(agent, 0.0) + reward
        action = int(rng.choice(np.flatnonzero(observation["action_mask"])))
        aec.step(action)
        obs, _, done, _, info = single.step(action)
    # A team reward: every robot's return is the final welfare.
    assert all(r == pytest.approx(info["welfare"]) for r in returns.values())
    assert len(returns) == 10

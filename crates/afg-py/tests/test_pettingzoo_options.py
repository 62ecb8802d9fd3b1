"""What multi-agent RL libraries expect of the PettingZoo environments beyond the
API: ``render_mode`` and ``max_cycles`` as PettingZoo's own take them, a global
``state()`` for centralised critics, failed robots kept as agents (as SMAC keeps dead
units), and SuperSuit's vector wrappers on missions with failures."""

from __future__ import annotations

from typing import Dict, List

import numpy as np
import pytest

import afg

pytest.importorskip("pettingzoo")
from pettingzoo.test import parallel_api_test  # noqa: E402

from afg.pettingzoo import allocation_v0, mission_v0  # noqa: E402

ROBOTS, TASKS = 12, 5
KEEP = TASKS  # the "keep" action


def _nearest(obs: Dict[str, Dict[str, np.ndarray]], agents: List[str]) -> Dict[str, int]:
    """Every agent heads for the nearest task it may take, or keeps its own."""
    actions = {}
    for agent in agents:
        o = obs[agent]
        rows = o["observation"][5:].reshape(TASKS, 9)
        allowed = np.flatnonzero(o["action_mask"][:TASKS])
        actions[agent] = int(allowed[np.argmin(rows[allowed, 3])]) if len(allowed) else KEEP
    return actions


def _episode(keep_failed: bool) -> List[float]:
    env = mission_v0.parallel_env(
        robots=ROBOTS, tasks=TASKS, preset="attrition", fail_share=0.5, keep_failed=keep_failed
    )
    obs, _ = env.reset(seed=3)
    rewards_seen, failed_seen = [], 0
    while env.agents:
        if keep_failed:
            assert env.agents == env.possible_agents, "the set of agents never changes"
        obs, rewards, terminations, truncations, _ = env.step(_nearest(obs, env.agents))
        rewards_seen.append(next(iter(rewards.values()), 0.0))
        if keep_failed and env.agents:
            assert not any(terminations.values()) and not any(truncations.values())
            for agent, o in obs.items():
                if not o["observation"].any():
                    # A failed robot: a zero view and only "keep".
                    assert list(o["action_mask"]) == [0] * TASKS + [1]
                    failed_seen += 1
    if keep_failed:
        assert failed_seen > 0, "robots failed in this mission"
    return rewards_seen


def test_kept_failed_robots_see_nothing_and_change_nothing() -> None:
    # The same mission and the same choices of the living robots: the same rewards,
    # whether the failed robots leave or stay as agents.
    assert _episode(keep_failed=True) == pytest.approx(_episode(keep_failed=False), rel=1e-12)
    parallel_api_test(
        mission_v0.parallel_env(robots=8, tasks=4, preset="attrition", fail_share=0.5, keep_failed=True),
        num_cycles=200,
    )


def test_max_cycles_truncates_every_agent() -> None:
    env = mission_v0.parallel_env(robots=ROBOTS, tasks=TASKS, preset="waves", max_cycles=3)
    obs, _ = env.reset(seed=1)
    for cycle in range(3):
        obs, _, terminations, truncations, _ = env.step(_nearest(obs, env.agents))
        assert all(truncations.values()) == (cycle == 2)
        assert not any(terminations.values())
    assert env.agents == []
    aec = allocation_v0.env(robots=4, tasks=2, max_cycles=1)
    aec.reset(seed=0)
    for agent in aec.agent_iter():
        _, _, terminated, truncated, _ = aec.last()
        aec.step(None if terminated or truncated else int(np.flatnonzero(aec.observe(agent)["action_mask"])[0]))
    for bad in (0, -1, 2.5, True):
        with pytest.raises(afg.InvalidInputError, match="max_cycles"):
            mission_v0.parallel_env(max_cycles=bad)
        with pytest.raises(afg.InvalidInputError, match="max_cycles"):
            allocation_v0.raw_env(max_cycles=bad)


def test_the_global_state_is_every_robots_view() -> None:
    env = mission_v0.parallel_env(robots=ROBOTS, tasks=TASKS, preset="attrition", fail_share=0.5, keep_failed=True)
    with pytest.raises(afg.RefusedError, match="reset"):
        env.state()
    obs, _ = env.reset(seed=2)
    while env.agents:
        state = env.state()
        assert env.state_space.contains(state)
        views = np.concatenate([obs[a]["observation"] for a in env.possible_agents])
        assert (state == views).all()
        obs, *_ = env.step(_nearest(obs, env.agents))
    aec = allocation_v0.raw_env(robots=5, tasks=3)
    aec.reset(seed=4)
    for agent in aec.agent_iter():
        state = aec.state()
        assert aec.state_space.contains(state)
        assert (state == np.concatenate([aec.observe(a)["observation"] for a in aec.possible_agents])).all()
        _, _, terminated, truncated, _ = aec.last()
        aec.step(None if terminated or truncated else int(np.flatnonzero(aec.observe(agent)["action_mask"])[0]))


def test_render_modes() -> None:
    for make in (mission_v0.parallel_env, allocation_v0.raw_env):
        assert make(render_mode=None).render_mode is None
        with pytest.raises(afg.InvalidInputError, match="render_mode 'human'"):
            make(render_mode="human")
    with pytest.raises(afg.InvalidInputError, match="render_mode 'rgb_array'"):
        allocation_v0.raw_env(render_mode="rgb_array")


def test_a_mission_renders_as_an_image_that_follows_the_robots() -> None:
    env = mission_v0.parallel_env(
        robots=8, tasks=3, preset="static", min_team=(2, 3), render_mode="rgb_array", render_size=128
    )
    assert mission_v0.parallel_env(robots=8, tasks=3).render() is None
    with pytest.raises(afg.RefusedError, match="reset"):
        env.render()
    observations, _ = env.reset(seed=2)
    first = env.render()
    assert first.shape == (128, 128, 3) and first.dtype == np.uint8
    assert (first != 255).any() and (first == 255).any()  # something drawn on white
    # Every robot heads for task 0: the picture changes as they move.
    env.step({a: 0 for a in env.agents})
    env.step({a: 3 for a in env.agents})
    assert (env.render() != first).any()


def test_supersuit_vector_wrappers_run_missions_with_failures() -> None:
    """SuperSuit's vector of two copies plays what the environment itself plays: the
    first copy (reset with seed 0) replayed action for action on a core environment
    gives the same rewards and observations until its episode ends."""
    ss = pytest.importorskip("supersuit")
    knobs = dict(robots=6, tasks=3, preset="attrition", fail_share=0.5, keep_failed=True)
    vec = ss.pettingzoo_env_to_vec_env_v1(mission_v0.parallel_env(**knobs))
    vec = ss.concat_vec_envs_v1(vec, 2, num_cpus=0, base_class="gymnasium")
    obs, _ = vec.reset(seed=0)
    assert obs["observation"].shape == (12, 5 + 9 * 3)
    core = mission_v0.parallel_env(**knobs)
    seen, _ = core.reset(seed=0)
    agents = core.possible_agents
    replayed, earned = 0, 0.0
    for _ in range(30):
        masks = obs["action_mask"]
        actions = np.array([int(np.flatnonzero(m)[0]) for m in masks])
        obs, rewards, terminated, truncated, _ = vec.step(actions)
        assert rewards.shape == (12,)
        if not core.agents:
            continue  # the first copy's episode ended: SuperSuit has reset it unseeded
        seen, core_rewards, core_terminated, _, _ = core.step(
            {a: int(actions[i]) for i, a in enumerate(agents) if a in core.agents}
        )
        assert rewards[:6].tolist() == pytest.approx([core_rewards.get(a, 0.0) for a in agents])
        if core.agents:
            for i, a in enumerate(agents):
                assert np.array_equal(obs["observation"][i], seen[a]["observation"])
        replayed += 1
        earned += sum(core_rewards.values())
    assert replayed >= 5 and earned > 0.0

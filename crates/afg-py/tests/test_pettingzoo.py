"""The PettingZoo AEC environment: PettingZoo's own API and seed tests, and step for
step the same episode as afg/Allocation-v0."""

from __future__ import annotations

import json
import math

import gymnasium as gym
import numpy as np
import pytest

import afg

pytest.importorskip("pettingzoo")
from pettingzoo.test import api_test, seed_test  # noqa: E402

import afg.gym  # noqa: E402,F401
from afg.pettingzoo import allocation_v0  # noqa: E402


def test_pettingzoo_api_and_seed_tests_pass() -> None:
    api_test(allocation_v0.env(robots=8, tasks=3), num_cycles=20)
    api_test(allocation_v0.env(robots=8, tasks=3, min_team=(2, 3), skills=2), num_cycles=20)
    seed_test(lambda: allocation_v0.env(robots=8, tasks=3), num_cycles=20)
    api_test(allocation_v0.env(robots=6, tasks=2, allow_void=True), num_cycles=20)


@pytest.mark.parametrize("teams", [{}, {"min_team": (2, 4), "skills": 2, "requires": (0, 1)}])
def test_the_aec_environment_is_the_gymnasium_one_step_by_step(teams: dict) -> None:
    rng = np.random.default_rng(0)
    aec = allocation_v0.env(robots=10, tasks=3, **teams)
    single = gym.make("afg/Allocation-v0", robots=10, tasks=3, **teams)
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
        if teams:
            assert np.array_equal(observation["team"], obs["team"].astype(np.float32))
            assert np.array_equal(observation["skills"], obs["skills"][t].astype(np.float32))
        else:
            assert "team" not in observation
        returns[agent] = returns.get(agent, 0.0) + reward
        action = int(rng.choice(np.flatnonzero(observation["action_mask"])))
        aec.step(action)
        obs, _, done, _, info = single.step(action)
    # A team reward: every robot's return is the final welfare.
    assert all(r == pytest.approx(info["welfare"]) for r in returns.values())
    assert len(returns) == 10


def test_mission_parallel_environment_passes_pettingzoo_tests() -> None:
    from pettingzoo.test import parallel_api_test, parallel_seed_test

    from afg.pettingzoo import mission_v0

    parallel_api_test(mission_v0.parallel_env(robots=8, tasks=4, preset="attrition"), num_cycles=200)
    parallel_api_test(
        mission_v0.parallel_env(robots=8, tasks=4, sensing=0.3, comm_radius=0.2, decide_every=2.0),
        num_cycles=200,
    )
    parallel_seed_test(lambda: mission_v0.parallel_env(robots=8, tasks=4, preset="poisson"), num_cycles=50)
    api_test(mission_v0.env(robots=6, tasks=3), num_cycles=50)
    seed_test(lambda: mission_v0.env(robots=6, tasks=3), num_cycles=50)


def test_mission_episode_returns_add_up_and_failed_robots_leave() -> None:
    from afg.pettingzoo import mission_v0

    env = mission_v0.parallel_env(robots=12, tasks=5, preset="attrition", fail_share=0.5)
    obs, _ = env.reset(seed=3)
    assert set(obs) == set(env.possible_agents)
    total, ended, played = 0.0, set(), []
    while env.agents:
        # Every agent heads for the nearest task it may take (or keeps its own).
        actions = {}
        for agent, o in obs.items():
            if agent not in env.agents:
                continue
            rows = o["observation"][5:].reshape(5, 9)
            allowed = np.flatnonzero(o["action_mask"][:5])
            actions[agent] = int(allowed[np.argmin(rows[allowed, 3])]) if len(allowed) else 5
        chosen = np.full(12, -1, dtype=np.int64)
        for agent, action in actions.items():
            chosen[int(agent.split("_")[1])] = action
        played.append(chosen)
        obs, rewards, terminations, truncations, _ = env.step(actions)
        assert len(set(rewards.values())) <= 1, "a team reward"
        total += next(iter(rewards.values()), 0.0)
        for agent in rewards:
            if terminations[agent] or truncations[agent]:
                assert agent not in ended and agent not in env.agents
                ended.add(agent)
    assert ended == set(env.possible_agents)
    # The team's return is the value of the work done, which the same mission run
    # through the core environment with the same actions reports step by step.
    seed = int(np.random.default_rng(3).integers(2**63))
    mission = afg.Mission.generate("attrition", 12, 5, seed=seed, fail_share=0.5)
    assert total == pytest.approx(_core_return(mission, played), rel=1e-12)
    # Robots that never move do no work: every reward is 0.
    obs, _ = env.reset(seed=3)
    while env.agents:
        _, rewards, _, _, _ = env.step({a: 5 for a in env.agents})
        assert set(rewards.values()) <= {0.0}
    with pytest.raises(ValueError, match="unknown preset"):
        mission_v0.parallel_env(preset="storm")


def test_the_mission_environment_steps_from_any_thread() -> None:
    import threading

    from afg.pettingzoo import mission_v0

    env = mission_v0.parallel_env(robots=6, tasks=3)
    env.reset(seed=0)
    errors, stepped = [], []

    def step() -> None:
        try:
            stepped.append(env.step({a: 0 for a in env.agents}))
        except BaseException as e:  # a panic would be a PanicException
            errors.append(e)

    thread = threading.Thread(target=step)
    thread.start()
    thread.join()
    assert errors == []
    # The step did what the same step does on the main thread: the robots moved.
    twin = mission_v0.parallel_env(robots=6, tasks=3)
    first, _ = twin.reset(seed=0)
    here = twin.step({a: 0 for a in twin.agents})
    (observations, rewards, *_), = stepped
    assert rewards == here[1]
    for agent, seen in here[0].items():
        assert np.array_equal(observations[agent]["observation"], seen["observation"])
    assert any(
        not np.array_equal(first[a]["observation"], here[0][a]["observation"]) for a in first
    )


def _core_return(mission: afg.Mission, played: list) -> float:
    """The return of the actions `played` on `mission` through `afg.MissionEnv`."""
    core = afg.MissionEnv(mission)
    total = 0.0
    for actions in played:
        reward, _, terminated, truncated = core.step(actions)
        total += reward
        if terminated or truncated:
            break
    return total


def test_a_steps_reward_is_the_reward_rate_times_the_time() -> None:
    """Robots already at their one task, epochs every 0.5: each epoch the coalition of
    n robots does log_eps(n + eps - 1) units of work per time unit, worth r each."""
    for robots in (1, 2):
        doc = json.loads(afg.Mission.generate("static", robots=robots, tasks=1, seed=4).to_json())
        task = doc["tasks"][0]
        for robot in doc["robots"]:
            robot["position"] = task["position"]
        env = afg.MissionEnv(afg.Mission.parse(json.dumps(doc)), decide_every=0.5)
        rate = math.log(robots + task["eps"] - 1) / math.log(task["eps"])
        time, total = 0.0, 0.0
        while True:
            reward, _, terminated, _ = env.step(np.zeros(robots, dtype=np.int64))
            dt = min(0.5, task["workload"] / rate - time)
            assert reward == pytest.approx(task["reward"] * rate * dt, abs=1e-9), (robots, time)
            time, total = time + 0.5, total + reward
            if terminated:
                break
        assert total == pytest.approx(task["reward"] * task["workload"], abs=1e-9)

"""The Gymnasium environments: the checker, seeds, returns, the oracle, the vector env."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import afg
import afg.gym  # noqa: F401  (registers afg/Allocation-v0)


def play(env, rng: np.random.Generator, **reset):
    """A random masked episode: the rewards, the last info and the steps taken."""
    obs, info = env.reset(**reset)
    rewards, steps, done = [], 0, False
    while not done:
        allowed = np.flatnonzero(info["action_mask"])
        obs, reward, done, truncated, info = env.step(int(rng.choice(allowed)))
        assert not truncated
        rewards.append(reward)
        steps += 1
    return rewards, info, steps


def test_the_gymnasium_checker_passes() -> None:
    check_env(gym.make("afg/Allocation-v0", robots=12, tasks=3).unwrapped, skip_render_check=True)


def test_seeds_reproduce_episodes_and_the_return_is_the_final_welfare() -> None:
    env = gym.make("afg/Allocation-v0", robots=20, tasks=5)
    a, info_a, steps = play(env, np.random.default_rng(0), seed=7)
    b, info_b, _ = play(env, np.random.default_rng(0), seed=7)
    c, _, _ = play(env, np.random.default_rng(0), seed=8)
    assert a == b and a != c and steps == 20
    assert sum(a) == pytest.approx(info_a["welfare"])
    assert (info_a["tasks"] == info_b["tasks"]).all()
    assert info_a["percent_of_opt"] == pytest.approx(100 * info_a["welfare"] / info_a["opt_welfare"])


def test_a_given_instance_has_one_step_per_robot_and_shaping_keeps_the_ranking() -> None:
    inst = afg.generate(robots=15, tasks=4, seed=3, capacity_slack=1.1)
    env = gym.make("afg/Allocation-v0", robots=15, tasks=4)
    rewards, info, steps = play(env, np.random.default_rng(1), options={"instance": inst})
    assert steps == 15 and sum(rewards) == pytest.approx(inst.welfare(info["tasks"]))
    shaped = gym.make("afg/Allocation-v0", robots=15, tasks=4, shaping="greedy")
    s, info_s, _ = play(shaped, np.random.default_rng(1), options={"instance": inst})
    greedy = afg.solve(inst, method="greedy").welfare
    # Potential-based shaping: the shaped return is the final welfare minus greedy's.
    assert sum(s) == pytest.approx(info_s["welfare"] - greedy)
    with pytest.raises(ValueError, match="robots"):
        env.reset(options={"instance": afg.generate(robots=9, tasks=4, seed=1)})


def test_the_oracle_gives_q_star_and_its_argmax_is_optimal() -> None:
    env = gym.make("afg/Allocation-v0", robots=10, tasks=3)
    obs, info = env.reset(seed=2, options={"oracle": True})
    done, ret = False, 0.0
    while not done:
        q = info["q_star"]
        assert np.isneginf(q[~info["action_mask"]]).all()
        obs, reward, done, _, info = env.step(int(np.argmax(q)))
        ret += reward
    assert info["percent_of_opt"] == pytest.approx(100.0)


def test_observations_have_the_declared_shapes_and_bad_actions_raise() -> None:
    env = gym.make("afg/Allocation-v0", robots=8, tasks=3)
    obs, info = env.reset(seed=0)
    assert obs["robot_features"].shape == obs["task_features"].shape == (8, 3)
    assert obs["actor"] == 0 and obs["action_mask"].tolist() == [1, 1, 1]
    assert env.unwrapped.action_masks().dtype == bool
    with pytest.raises(ValueError, match="action 5 is not one of 0..3"):
        env.step(5)
    with pytest.raises(ValueError, match="not one of"):
        env.step(-3)
    for _ in range(8):
        obs, *_ = env.step(0)
    assert obs["actor"] == 8
    with pytest.raises(ValueError, match="over"):
        env.step(0)


def test_the_vector_env_equals_k_single_envs_step_by_step() -> None:
    k, n, m = 3, 12, 4
    venv = gym.make_vec("afg/Allocation-v0", num_envs=k, vectorization_mode="vector_entry_point", robots=n, tasks=m)
    obs, info = venv.reset(seed=11)
    seeds = [int(s) for s in np.random.default_rng(11).integers(2**63, size=k)]
    singles = [afg.EnvCore(afg.generate(n, m, s)) for s in seeds]
    rng = np.random.default_rng(0)
    for t in range(n + 1):
        for i, core in enumerate(singles):
            nu, mu, actor, mask = core.observation()
            assert obs["actor"][i] == actor and (obs["action_mask"][i] == mask).all()
            assert (obs["task_features"][i] == mu).all() and (obs["robot_features"][i] == nu).all()
        if t == n:
            break
        actions = np.array([rng.choice(np.flatnonzero(info["action_mask"][i])) for i in range(k)])
        obs, rewards, terminated, truncated, info = venv.step(actions)
        for i, core in enumerate(singles):
            reward, done = core.step(int(actions[i]))
            assert rewards[i] == reward and terminated[i] == done
    assert terminated.all() and "welfare" in info
    # The next step resets every sub-environment (reward 0), then play goes on.
    obs, rewards, terminated, _, info = venv.step(np.zeros(k, dtype=np.int64))
    assert (rewards == 0).all() and not terminated.any() and (obs["actor"] == 0).all()


def test_the_vector_env_copies_its_observations_unless_told_not_to() -> None:
    make = lambda copy: gym.make_vec(  # noqa: E731
        "afg/Allocation-v0", num_envs=2, vectorization_mode="vector_entry_point", robots=6, tasks=3, copy=copy
    )
    for copy in (True, False):
        venv = make(copy)
        first, _ = venv.reset(seed=1)
        kept = first["robot_features"].copy()
        second, *_ = venv.step(np.zeros(2, dtype=np.int64))
        assert (second["robot_features"] != kept).any()  # robot 0 joined task 0
        # A copy keeps the old observation; the shared buffer now holds the new one.
        assert (first["robot_features"] == kept).all() == copy
        assert (second["robot_features"] is first["robot_features"]) == (not copy)


def test_grapes_game_adds_the_void_action() -> None:
    env = gym.make("afg/Allocation-v0", robots=10, tasks=3, allow_void=True)
    check_env(env.unwrapped, skip_render_check=True)
    assert env.action_space.n == 4
    # Random masked play: staying out gives 0, the return is the final welfare.
    rewards, info, steps = play(env, np.random.default_rng(3), seed=5)
    assert steps == 10 and sum(rewards) == pytest.approx(info["welfare"])
    # The oracle's argmax reaches the optimum of GRAPE's game, staying out included.
    obs, info = env.reset(seed=4, options={"oracle": True})
    stayed, done = 0, False
    while not done:
        q = info["q_star"]
        assert q.shape == (4,) and np.isneginf(q[~info["action_mask"]]).all()
        action = int(np.argmax(q))
        stayed += action == 3
        obs, reward, done, _, info = env.step(action)
        if action == 3:
            assert reward == 0.0
    assert info["percent_of_opt"] == pytest.approx(100.0)
    assert (info["tasks"] == -1).sum() == stayed
    # A paper-game instance masks the void out; the paper's environment refuses the void.
    paper = afg.generate(robots=10, tasks=3, seed=1)
    obs, info = env.reset(options={"instance": paper})
    assert obs["action_mask"].tolist() == [1, 1, 1, 0]
    with pytest.raises(ValueError, match="paper's game"):
        env.step(3)
    void = afg.generate(robots=10, tasks=3, seed=1, allow_void=True)
    with pytest.raises(ValueError, match="allow_void=True"):
        gym.make("afg/Allocation-v0", robots=10, tasks=3).reset(options={"instance": void})
    with pytest.raises(ValueError, match="shaping"):
        gym.make("afg/Allocation-v0", robots=10, tasks=3, allow_void=True, shaping="greedy")


def test_the_void_vector_env_equals_single_envs() -> None:
    k, n, m = 2, 8, 3
    venv = gym.make_vec(
        "afg/Allocation-v0", num_envs=k, vectorization_mode="vector_entry_point",
        robots=n, tasks=m, allow_void=True,
    )
    obs, info = venv.reset(seed=2)
    seeds = [int(s) for s in np.random.default_rng(2).integers(2**63, size=k)]
    singles = [afg.EnvCore(afg.generate(n, m, s, allow_void=True), void_action=True) for s in seeds]
    rng = np.random.default_rng(1)
    for t in range(n):
        for i, core in enumerate(singles):
            assert (obs["action_mask"][i] == core.observation()[3]).all()
        actions = np.array([rng.choice(np.flatnonzero(info["action_mask"][i])) for i in range(k)])
        obs, rewards, terminated, _, info = venv.step(actions)
        for i, core in enumerate(singles):
            assert (rewards[i], terminated[i]) == core.step(int(actions[i]))
    assert terminated.all()


def test_the_team_vector_env_equals_single_team_envs() -> None:
    k, n, m = 3, 8, 3
    teams = dict(min_team=(2, 9), skills=2, requires=(1, 2))
    venv = gym.make_vec(
        "afg/Allocation-v0", num_envs=k, vectorization_mode="vector_entry_point", robots=n, tasks=m, **teams
    )
    obs, info = venv.reset(seed=5)
    assert venv.observation_space.contains(obs)
    assert obs["team"].shape == (k, m, 5) and obs["skills"].shape == (k, n, 2)
    seeds = [int(s) for s in np.random.default_rng(5).integers(2**63, size=k)]
    singles = [gym.make("afg/Allocation-v0", robots=n, tasks=m, **teams) for _ in range(k)]
    single_obs = [env.reset(options={"instance": afg.generate(n, m, s, **teams)})[0] for env, s in zip(singles, seeds)]
    # Some task here has a threshold above the robots: masked in the vector env too.
    assert any(not o["action_mask"].all() for o in single_obs)
    rng = np.random.default_rng(3)
    for _ in range(n):
        for i, o in enumerate(single_obs):
            for key, value in o.items():
                assert np.array_equal(obs[key][i], value), key
        assert np.array_equal(venv.unwrapped.action_masks(), info["action_mask"])
        actions = np.array([rng.choice(np.flatnonzero(info["action_mask"][i])) for i in range(k)])
        obs, rewards, terminated, _, info = venv.step(actions)
        for i, env in enumerate(singles):
            single_obs[i], reward, done, _, _ = env.step(int(actions[i]))
            assert np.isclose(rewards[i], reward) and terminated[i] == done
    assert terminated.all()

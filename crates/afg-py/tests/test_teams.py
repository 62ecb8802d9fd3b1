"""The team games from Python: thresholds and skills on instances, the generator's
knobs, the exact optimum with its bound and gap, and allocators that refuse."""

from __future__ import annotations

import json
import math
import warnings
from pathlib import Path

import numpy as np
import pytest

import afg

ROOT = Path(__file__).resolve().parents[3]


def test_team_instances_expose_thresholds_and_skills_as_arrays() -> None:
    inst = afg.Instance(
        robots=np.array([[1.0, 0.0], [0.0, 1.0]]),
        tasks=np.array([[0.0, 0.0], [10.0, 0.0]]),
        rewards=[4.0, 1.0],
        eps=[2.0, 2.0],
        min_team=[2, 1],
        skills=[[1, 0], [0, 1]],
        requires=[[1, 1], []],
    )
    assert inst.min_team.tolist() == [2, 1]
    assert inst.skills.tolist() == [[1, 0], [0, 1]]
    assert inst.requires.tolist() == [[1, 1], [0, 0]]
    # Both robots at task 0: a complete team holding both skills, F(2) = 4 log2 3.
    assert inst.welfare([0, 0]) == pytest.approx(4 * np.log2(3) - 2)
    # One robot there alone earns nothing and pays its travel.
    assert inst.welfare([0, 1]) == pytest.approx(-1 + 1 - np.hypot(10, 1))
    assert afg.Instance.parse(inst.to_json()).skills.tolist() == [[1, 0], [0, 1]]


def test_the_generator_draws_team_games_like_afg_gen() -> None:
    inst = afg.generate(40, 5, seed=3, min_team=(2, 6), skills=2, skill_share=0.5, requires=(0, 2))
    assert inst.min_team.min() >= 2 and inst.min_team.max() <= 6
    assert inst.skills.shape == (40, 2) and set(np.unique(inst.skills)) <= {0, 1}
    assert inst.requires.shape == (5, 2) and inst.requires.max() <= 2
    plain = afg.generate(40, 5, seed=3)
    assert np.array_equal(plain.robots, inst.robots)
    assert plain.min_team.tolist() == [1] * 5 and plain.skills.shape == (40, 0)
    # The repr shows the teams and skills (and nothing of them on the paper's game).
    lo, hi = inst.min_team.min(), inst.min_team.max()
    assert repr(inst) == f"Instance(robots=40, tasks=5, beta=1.0, min_team={lo}..{hi}, skills=2)"
    assert repr(plain) == "Instance(robots=40, tasks=5, beta=1.0)"
    # A task no team can staff is drawn with a warning, as `afg gen` and `afg mission
    # gen` give it; none where every task can be staffed.
    with pytest.warns(UserWarning, match="no team can staff tasks 0, 1"):
        afg.generate(4, 2, seed=1, min_team=(5, 5))
    with pytest.warns(UserWarning, match="no team can staff tasks 0, 1"):
        afg.Mission.generate("static", robots=4, tasks=2, seed=1, min_team=(5, 5))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        afg.generate(4, 2, seed=1, min_team=(2, 2))


def test_the_exact_optimum_reaches_the_committed_optima_with_a_true_bound_and_gap() -> None:
    """The committed team games' certified optima (proven independently by HiGHS in
    test_teams_milp.py): the exact solver reaches each; stopped at its root, its bound
    is above the optimum and its gap is (bound - welfare) / welfare."""
    checked = 0
    for game in ("thresholds", "skills", "both"):
        lines = (ROOT / "datasets" / f"teams-{game}.jsonl").read_text().splitlines()
        optima = json.loads((ROOT / "datasets" / f"teams-{game}.optima.json").read_text())
        for line, optimum in zip(lines, optima):
            if optimum["robots"] > 20:
                continue
            inst = afg.Instance.parse(line)
            exact = afg.solve(inst, method="opt")
            assert exact.welfare == pytest.approx(optimum["welfare"], rel=1e-9, abs=1e-9)
            assert exact.stats["bound"] == pytest.approx(optimum["welfare"], rel=1e-9, abs=1e-9)
            assert exact.stats["gap"] == 0.0
            cut = afg.solve(inst, method="opt", time_limit=1e-9)
            assert cut.stats["bound"] >= optimum["welfare"] - 1e-9
            assert cut.welfare <= optimum["welfare"] + 1e-9
            expected = (cut.stats["bound"] - cut.welfare) / abs(cut.welfare)
            assert cut.stats["gap"] == pytest.approx(expected, rel=1e-9, abs=1e-12)
            checked += 1
    assert checked >= 10


def test_the_exact_optimum_reports_its_bound_and_gap() -> None:
    inst = afg.generate(100, 10, seed=1, min_team=(10, 20))
    exact = afg.solve(inst, method="opt")
    assert exact.stats["gap"] == 0.0
    assert exact.stats["bound"] == pytest.approx(exact.welfare)
    cut = afg.solve(inst, method="opt", time_limit=1e-9)
    assert cut.welfare <= exact.welfare + 1e-9
    assert cut.stats["bound"] >= exact.welfare - 1e-9
    greedy = afg.solve(inst, method="greedy")
    assert greedy.welfare <= exact.welfare + 1e-9
    assert "bound" not in greedy.stats
    with pytest.raises(afg.InvalidInputError, match="for the exact optimum"):
        afg.solve(inst, method="greedy", time_limit=1.0)
    # "% of OPT" of another method: against the optimum within reference_time_limit
    # (of its bound, said in the stats, where not proven), or nothing at all.
    assert greedy.stats["reference_proven"] == 1.0
    assert greedy.stats["reference_welfare"] == pytest.approx(exact.welfare)
    rushed = afg.solve(inst, method="nearest", reference_time_limit=1e-9)
    assert rushed.stats["reference_proven"] == 0.0
    assert rushed.stats["reference_bound"] >= exact.welfare - 1e-9
    assert rushed.percent_of_opt == pytest.approx(100 * rushed.welfare / rushed.stats["reference_bound"])
    alone = afg.solve(inst, method="nearest", reference=False)
    assert alone.percent_of_opt is None and "reference_bound" not in alone.stats
    with pytest.raises(afg.InvalidInputError, match="finite and positive"):
        afg.solve(inst, method="nearest", reference_time_limit=0.0)
    # The same door as the command line and missions: a limit must be positive.
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(afg.InvalidInputError, match="finite and positive"):
            afg.solve(inst, method="opt", time_limit=bad)
    with pytest.raises(afg.InvalidInputError, match="finite, non-negative"):
        afg.solve(inst, method="opt", gap=-0.01)
    with pytest.raises(afg.InvalidInputError, match="for the exact optimum"):
        afg.solve(inst, method="nearest", gap=0.01)


def _slow_skill_game() -> afg.Instance:
    """A skill game whose proof takes the exact search longer than ten seconds (the
    `sparse-skills` game of seed 7 that docs/families.md's wider table leaves unproven
    after 10 s)."""
    return afg.generate(100, 20, seed=7, family="sparse-skills")


def test_a_gap_target_stops_the_exact_search_with_a_certified_gap() -> None:
    inst = _slow_skill_game()
    near = afg.solve(inst, method="opt", gap=0.1, reference=False)
    assert 0.0 < near.stats["gap"] <= 0.1
    assert near.stats["bound"] == pytest.approx(near.welfare * (1 + near.stats["gap"]))


def test_the_exact_search_starts_from_an_assignment_given() -> None:
    inst = afg.generate(30, 6, seed=6, family="sparse-skills")
    best = afg.solve(inst, method="opt", reference=False)
    assert best.stats["gap"] == 0
    # Stopped at its first certified gap under 50 %, the search alone answers its
    # first dive's assignment, short of the optimum; from the optimum, the optimum.
    alone = afg.solve(inst, method="opt", gap=0.5, reference=False)
    assert alone.welfare < best.welfare - 1e-9
    started = afg.solve(inst, method="opt", gap=0.5, reference=False, start=best.tasks)
    assert started.welfare == pytest.approx(best.welfare, abs=1e-9)
    assert list(started.tasks) == list(best.tasks)
    with pytest.raises(afg.InvalidInputError, match="for the exact optimum"):
        afg.solve(inst, method="nearest", start=best.tasks)
    with pytest.raises(afg.InvalidInputError):
        afg.solve(inst, method="opt", start=best.tasks[:-1])


def test_ctrl_c_stops_the_exact_search_at_its_next_step() -> None:
    import _thread
    import threading
    import time

    import signal

    inst = _slow_skill_game()
    # Python's own Ctrl-C handler, whatever an earlier test (Ray's, say) left in its place:
    # interrupt_main does nothing where SIGINT is not handled by Python's default.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        timer = threading.Timer(0.5, _thread.interrupt_main)
        start = time.monotonic()
        timer.start()
        with pytest.raises(KeyboardInterrupt):
            afg.solve(inst, method="opt", reference=False)
        timer.join()
        assert time.monotonic() - start < 10.0
    finally:
        signal.signal(signal.SIGINT, previous)


def test_bad_team_input_and_refusals_are_clear_errors() -> None:
    robots, tasks = np.zeros((2, 2)), np.zeros((1, 2))
    with pytest.raises(afg.InvalidInputError, match="min_team 0"):
        afg.Instance(robots, tasks, [1.0], [2.0], min_team=[0])
    with pytest.raises(afg.InvalidInputError, match="skills holds -1"):
        afg.Instance(robots, tasks, [1.0], [2.0], skills=[[-1], [0]])
    with pytest.raises(afg.InvalidInputError, match="min_team holds 1000000000000: .* from 0 to 4294967295"):
        afg.Instance(robots, tasks, [1.0], [2.0], min_team=[10**12])
    with pytest.raises(afg.InvalidInputError, match="lists 2 skills but robot 0 lists 1"):
        afg.Instance(robots, tasks, [1.0], [2.0], skills=[[1], [0]], requires=[[1, 1]])
    skills = afg.generate(20, 4, seed=2, skills=2)
    with pytest.raises(afg.InvalidInputError, match="does not play games with skill requirements"):
        afg.solve(skills, method="da")


def test_team_missions_wait_for_their_teams_and_refuse_what_cannot_play_them() -> None:
    mission = afg.Mission.generate("waves", robots=40, tasks=8, seed=3, min_team=(2, 5))
    assert mission.to_json() == afg.Mission.generate("waves", robots=40, tasks=8, seed=3, min_team=(2, 5)).to_json()
    assert '"min_team"' in mission.to_json()
    metrics = afg.run_mission(mission, method="opt").metrics
    waiting = metrics["waiting"]
    assert isinstance(waiting["by_task"], np.ndarray) and waiting["by_task"].shape == (8,)
    assert waiting["total"] == pytest.approx(waiting["by_task"].sum()) and waiting["total"] > 0.0
    # By hand: robots at x = 0 and 4, one task at x = 1 of workload 3 that needs both.
    # Robot 0 arrives at t = 1 and waits for robot 1 (t = 3); the pair works at
    # log2(3) per time unit from then.
    hand = afg.Mission.parse(json.dumps({
        "format": "afg-mission", "version": 1, "beta": 1.0, "horizon": 50.0,
        "robots": [{"position": {"x": x, "y": 0.0}, "speed": 1.0} for x in (0.0, 4.0)],
        "tasks": [{"position": {"x": 1.0, "y": 0.0}, "reward": 1.0, "eps": 2.0,
                   "workload": 3.0, "appears": 0.0, "min_team": 2}],
    }))
    for method in ("opt", "greedy"):
        by_hand = afg.run_mission(hand, method=method).metrics
        assert by_hand["waiting"]["total"] == pytest.approx(2.0, abs=1e-9)
        assert by_hand["waiting"]["by_task"].tolist() == pytest.approx([2.0], abs=1e-9)
        assert by_hand["makespan"] == pytest.approx(3.0 + 3.0 / math.log2(3.0), abs=1e-9)
    assert afg.run_mission(mission, method="opt", time_limit=5.0).metrics["gap_max"] == 0.0
    with pytest.raises(afg.InvalidInputError, match="for the exact optimum"):
        afg.run_mission(mission, method="greedy", time_limit=1.0)
    # The auction plays it, at epsilon 0.01 by default on a team mission; given 0.001
    # (the paper's game's default) it warns that teams want a larger one.
    small = afg.Mission.generate("static", robots=12, tasks=3, seed=1, min_team=(2, 3))
    with pytest.warns(UserWarning, match="epsilon=0.01"):
        afg.run_mission(small, method="auction", epsilon=0.001)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        default = afg.run_mission(small, method="auction")
        assert default.metrics["tasks_done"] == 3
        given = afg.run_mission(small, method="auction", epsilon=0.01).metrics
        assert given["swarm"]["rounds"] == default.metrics["swarm"]["rounds"]
        assert given["reward_done"] == default.metrics["reward_done"]
    # A mission without teams has no waiting metric.
    assert "waiting" not in afg.run_mission(afg.Mission.generate("waves", 40, 8, seed=3)).metrics
    skilled = afg.Mission.generate("waves", robots=40, tasks=8, seed=3, min_team=(2, 4), skills=2, requires=(0, 1))
    for method in ("greedy", "grape"):
        with pytest.raises(afg.AfgError, match="does not play games with skill requirements"):
            afg.run_mission(skilled, method=method)
    with pytest.raises(afg.InvalidInputError, match="need skills"):
        afg.Mission.generate("waves", robots=10, tasks=3, requires=(1, 2))


def test_mission_env_observes_teams_and_masks_what_no_team_can_staff():
    pytest.importorskip("pettingzoo")
    from afg.pettingzoo import mission_v0

    tasks, skills = 6, 2
    knobs = dict(min_team=(2, 4), skills=skills, requires=(1, 1))
    mission = afg.Mission.generate("static", 12, tasks, seed=3, **knobs)
    assert mission.min_team.shape == (tasks,) and mission.requires.shape == (tasks, skills)
    assert mission.skills.shape == (12, skills) and mission.min_team.min() >= 2
    core = afg.MissionEnv(mission, teams=True)
    length = 5 + skills + tasks * (13 + skills)
    assert core.observation_len == length
    observations = core.observations()
    # Each robot's own skills follow its five features; each task's threshold over N
    # follows its nine.
    assert np.array_equal(observations[:, 5 : 5 + skills], mission.skills)
    row = 5 + skills
    assert np.allclose(observations[0, row + 9], mission.min_team[0] / 12)

    env = mission_v0.parallel_env(robots=12, tasks=tasks, preset="static", **knobs)
    assert env.observation_space("robot_0")["observation"].shape == (length,)
    observed, _ = env.reset(seed=3)
    assert all(o["observation"].shape == (length,) for o in observed.values())
    from pettingzoo.test import parallel_api_test

    parallel_api_test(mission_v0.parallel_env(robots=8, tasks=4, preset="waves", **knobs), num_cycles=100)
    # Without team knobs the observation is the plain one.
    plain = mission_v0.parallel_env(robots=12, tasks=tasks, preset="static")
    assert plain.observation_space("robot_0")["observation"].shape == (5 + 9 * tasks,)
    # A threshold above the robots masks the task for everyone.
    big = afg.Mission.generate("static", 3, 2, seed=1, min_team=(4, 4))
    masks = afg.MissionEnv(big, teams=True).masks()
    assert not masks[:, :2].any() and masks[:, 2].all()


def test_the_gym_environment_observes_teams():
    gym = pytest.importorskip("gymnasium")
    import afg.gym  # noqa: F401

    env = gym.make("afg/Allocation-v0", robots=8, tasks=3, min_team=(2, 3), skills=2, requires=(1, 1))
    obs, info = env.reset(seed=4)
    assert obs["team"].shape == (3, 5) and obs["skills"].shape == (8, 2)
    assert env.observation_space.contains(obs)
    core = env.unwrapped
    inst = core._core.instance
    assert np.allclose(obs["team"][:, 0], inst.min_team / 8)
    assert np.array_equal(obs["skills"], inst.skills)
    assert not obs["team"][:, 1].any() and not obs["team"][:, 2].any()
    # Every robot joins task 0: its members grow one by one, its team completes once
    # the threshold is met and its skills held, and the episode's return is the team
    # game's welfare.
    total, done = 0.0, False
    while not done:
        obs, reward, done, _, info = env.step(0)
        total += reward
    assert np.isclose(obs["team"][0, 1], 8 / inst.min_team[0])
    assert obs["team"][0, 2] == float(np.all(inst.skills.sum(axis=0) >= inst.requires[0]))
    assert abs(total - info["welfare"]) < 1e-9
    # A task no team can staff (a threshold of 5 with 4 robots) is masked.
    inst = afg.Instance(
        np.full((4, 2), 0.5), np.array([[0.1, 0.1], [0.9, 0.9]]), [4.0, 4.0], [2.0, 2.0],
        min_team=[2, 5],
    )
    small = gym.make("afg/Allocation-v0", robots=4, tasks=2, min_team=(1, 2))
    obs, info = small.reset(options={"instance": inst})
    assert obs["action_mask"].tolist() == [1, 0] and info["action_mask"].tolist() == [True, False]
    assert small.unwrapped.action_masks().tolist() == [True, False]
    # An instance with another number of skills than the spaces is refused.
    other = afg.generate(8, 3, 1, min_team=(2, 3), skills=1)
    with pytest.raises(afg.InvalidInputError, match="the instance has 1 skills, the environment's spaces 2"):
        env.reset(options={"instance": other})


def test_the_staffing_models_play_their_games_or_refuse() -> None:
    root = Path(__file__).resolve().parents[3]
    for seed in (1, 2):
        inst = afg.generate(100, 10, seed=seed, min_team=(10, 20), skills=2, skill_share=0.2, requires=(1, 3))
        exact = afg.solve(inst, method="opt")
        learned = afg.solve(inst, model=str(root / "models" / "ours" / "staffing_skills"))
        assert 0.95 * exact.welfare <= learned.welfare <= exact.welfare + 1e-9
    with pytest.raises(afg.InvalidInputError, match="trained without skills"):
        afg.solve(inst, model=str(root / "models" / "ours" / "staffing_teams"))


def test_arguments_are_read_as_python_writes_them_and_refused_as_afg_errors():
    # Pairs as lists or numpy arrays, not only tuples.
    a = afg.generate(robots=30, tasks=3, seed=1, min_team=[2, 4], skills=2, requires=np.array([1, 1]))
    b = afg.generate(robots=30, tasks=3, seed=1, min_team=(2, 4), skills=2, requires=(1, 1))
    np.testing.assert_array_equal(a.min_team, b.min_team)
    mission = afg.Mission.generate("waves", robots=10, tasks=4, workload=[1.0, 2.0], min_team=np.array([1, 2]))
    assert mission.num_tasks == 4
    # Whole numbers as numpy integers, whole floats and bools, in vectors and matrices.
    robots = np.array([[0.0, 0.0], [1.0, 0.0]])
    tasks = np.array([[0.5, 0.5]])
    inst = afg.Instance(robots, tasks, [2.0], [2.0], min_team=np.array([2.0]),
                        skills=np.array([[True], [False]]), requires=np.array([[1]], dtype=np.int32))
    np.testing.assert_array_equal(inst.min_team, [2])
    np.testing.assert_array_equal(inst.skills, [[1], [0]])
    # Everything else is an afg.InvalidInputError naming the value, never a TypeError or OverflowError.
    for call, says in [
        (lambda: afg.generate(robots=-1), "got -1"),
        (lambda: afg.generate(robots=10, min_team="ab"), "string"),
        (lambda: afg.generate(robots=10, min_team=(1, 2, 3)), "3 values"),
        (lambda: afg.generate(robots=10, rewards=[1.0, "x"]), "expected a number"),
        (lambda: afg.generate(robots=2.5), "whole number"),
        (lambda: afg.Mission.generate("waves", robots=10, tasks=4, seed=-3), "got -3"),
        (lambda: afg.Instance(robots, tasks, [2.0], [2.0], min_team=[1.5]), "whole number"),
        (lambda: afg.Instance(robots, tasks, [2.0], [2.0], skills=np.array([[0.5], [1.0]]), requires=[[1]]), "whole number"),
        (lambda: afg.Instance(robots, tasks, [2.0], [2.0], min_team=[10**30]), "out of range"),
    ]:
        with pytest.raises(afg.InvalidInputError, match=says):
            call()


def test_a_game_too_large_for_memory_is_refused_not_a_crash() -> None:
    # 10¹¹ robot–task pairs: terabytes for the exact solver, refused before it starts.
    inst = afg.generate(1_000_000, 100_000, seed=1, min_team=(2, 4))
    with pytest.raises(afg.InvalidInputError, match=r"1000000 × 100000 game needs about [0-9.]+ GB"):
        afg.solve(inst, method="opt")
    with pytest.raises(afg.InvalidInputError, match="at most 64 skills"):
        afg.generate(10, 2, skills=1_000_000)


def test_named_families_are_drawn_by_name_and_seeded() -> None:
    names = afg.families()
    assert names[:2] == ["scarce", "skills"] and "mixed" in names and len(names) == 10
    for name in names:
        inst = afg.generate(60, 6, seed=2, family=name)
        assert inst.to_json() == afg.generate(60, 6, seed=2, family=name).to_json()
        assert f'"family":"{name}"' in inst.to_json()
    void = afg.generate(60, 6, seed=2, family="void-capacity")
    assert void.allow_void and void.beta == 2.0
    assert afg.generate(60, 6, seed=2, family="void-capacity", beta=0.5).beta == 0.5
    with pytest.raises(afg.InvalidInputError, match="one of scarce, skills"):
        afg.generate(60, 6, family="uniformish")

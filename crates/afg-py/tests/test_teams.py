"""The team games from Python: thresholds and skills on instances, the generator's
knobs, the exact optimum with its bound and gap, and allocators that refuse."""

from __future__ import annotations

import numpy as np
import pytest

import afg


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


def test_the_exact_optimum_reports_its_bound_and_gap() -> None:
    inst = afg.generate(100, 10, seed=1, min_team=(10, 20))
    exact = afg.solve(inst, method="opt")
    assert exact.stats["gap"] == 0.0
    assert exact.stats["bound"] == pytest.approx(exact.welfare)
    cut = afg.solve(inst, method="opt", time_limit=0.0)
    assert cut.welfare <= exact.welfare + 1e-9
    assert cut.stats["bound"] >= exact.welfare - 1e-9
    greedy = afg.solve(inst, method="greedy")
    assert greedy.welfare <= exact.welfare + 1e-9
    assert "bound" not in greedy.stats
    with pytest.raises(afg.InvalidInputError, match="time_limit applies to method=\"opt\""):
        afg.solve(inst, method="greedy", time_limit=1.0)


def test_bad_team_input_and_refusals_are_clear_errors() -> None:
    robots, tasks = np.zeros((2, 2)), np.zeros((1, 2))
    with pytest.raises(afg.InvalidInputError, match="min_team 0"):
        afg.Instance(robots, tasks, [1.0], [2.0], min_team=[0])
    with pytest.raises(afg.InvalidInputError, match="skills holds -1"):
        afg.Instance(robots, tasks, [1.0], [2.0], skills=[[-1], [0]])
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
    assert waiting["total"] == pytest.approx(waiting["by_task"].sum()) and waiting["total"] >= 0.0
    assert afg.run_mission(mission, method="opt", time_limit=5.0).metrics["gap_max"] == 0.0
    with pytest.raises(afg.InvalidInputError, match="for the exact optimum"):
        afg.run_mission(mission, method="greedy", time_limit=1.0)
    # A mission without teams has no waiting metric.
    assert "waiting" not in afg.run_mission(afg.Mission.generate("waves", 40, 8, seed=3)).metrics
    skilled = afg.Mission.generate("waves", robots=40, tasks=8, seed=3, min_team=(2, 4), skills=2, requires=(0, 1))
    for method in ("greedy", "grape"):
        with pytest.raises(afg.AfgError, match="does not play games with skill requirements"):
            afg.run_mission(skilled, method=method)
    with pytest.raises(afg.InvalidInputError, match="need skills"):
        afg.Mission.generate("waves", robots=10, tasks=3, requires=(1, 2))

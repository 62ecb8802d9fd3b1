"""afg.schedule and afg.score_schedule: DCMRTA's published routes scored as published,
a hand-computed schedule, plans that their own scoring confirms, refusals as AfgError."""

import json
import pathlib

import numpy as np
import pytest

import afg

SET = pathlib.Path(__file__).resolve().parents[3] / "datasets" / "dcmrta-20a50t"


def published_routes():
    with open(SET / "dcmrta-20a50t-routes.jsonl") as f:
        return [json.loads(line)["routes"] for line in f]


def test_the_published_routes_score_as_published():
    instances = afg.ScheduleInstance.read(SET / "dcmrta-20a50t.jsonl")
    with open(SET / "dcmrta-20a50t-published.jsonl") as f:
        published = [json.loads(line)["methods"]["CTAS-D_300s"] for line in f]
    for inst, routes, row in list(zip(instances, published_routes(), published))[:10]:
        run = afg.score_schedule(inst, [np.asarray(r) for r in routes])
        assert abs(run["makespan"] - row["makespan"]) < 1e-9
        assert abs(run["travel"] - row["travel_dist"]) < 1e-9
        assert abs(run["waiting"] - row["waiting_time"]) < 1e-9
    strict = afg.score_schedule(instances[0], published_routes()[0], max_wait=10)
    assert not strict["valid"]
    assert strict["long_waits"].shape[1] == 3 and (strict["long_waits"][:, 2] > 10).all()


def test_a_hand_schedule():
    inst = afg.ScheduleInstance.parse(
        '{"speed":1,"max_wait":10,"depots":[[0,0]],'
        '"robots":[{"x":0,"y":0,"depot":0},{"x":0,"y":0,"depot":0}],'
        '"tasks":[{"x":4,"y":0,"min_team":2,"duration":2},{"x":0,"y":3,"min_team":1,"duration":1}]}'
    )
    run = afg.score_schedule(inst, [[0], [1, 0]])
    assert run["makespan"] == 15.0 and run["longest_wait"] == 5.0 and run["waiting"] == 2.5
    np.testing.assert_array_equal(run["start"], [9.0, 3.0])
    # per robot: working (2 + 3) / 2, driving (8 + 12) / 2, waiting 5 / 2, nobody idle
    assert run["time_use"] == {"working": 2.5, "driving": 10.0, "waiting": 2.5, "idle": 0.0}
    assert "robots=2, tasks=2" in repr(inst)


@pytest.mark.parametrize("family", ["dcmrta", "heteromrta"])
def test_a_plan_is_valid_its_scoring_agrees_and_the_bound_lies_below(family):
    inst = afg.ScheduleInstance.generate(family, robots=9, tasks=20, seed=3)
    plan = afg.schedule(inst, steps=2000, seed=1)
    assert plan["valid"] and plan["longest_wait"] <= inst.max_wait
    again = afg.score_schedule(inst, plan["routes"])
    assert again["makespan"] == plan["makespan"]
    assert plan["bound"] <= plan["makespan"] and plan["bound"] == inst.lower_bound()
    assert abs(plan["gap"] - (1 - plan["bound"] / plan["makespan"])) < 1e-12
    assert all(r.dtype == np.int64 for r in plan["routes"])
    same = afg.schedule(inst, steps=2000, seed=1)
    assert [r.tolist() for r in same["routes"]] == [r.tolist() for r in plan["routes"]]


def test_refusals_are_afg_errors_naming_the_problem():
    inst = afg.ScheduleInstance.parse(
        '{"speed":1,"max_wait":10,"depots":[[0,0]],'
        '"robots":[{"x":0,"y":0,"depot":0},{"x":0,"y":0,"depot":0}],'
        '"tasks":[{"x":1,"y":0,"min_team":2,"duration":1},{"x":0,"y":1,"min_team":2,"duration":1}]}'
    )
    with pytest.raises(afg.InvalidInputError, match="robot 0 waits at task 0"):
        afg.score_schedule(inst, [[0, 1], [1, 0]])
    with pytest.raises(afg.InvalidInputError, match="leaves out task 1"):
        afg.score_schedule(inst, [[0], [0]])
    with pytest.raises(afg.InvalidInputError, match="task ids start at 0"):
        afg.score_schedule(inst, [[0, 1], [-1]])
    with pytest.raises(afg.InvalidInputError, match="time limit"):
        afg.schedule(inst, time_limit=float("nan"))
    with pytest.raises(afg.InvalidInputError, match="unknown family"):
        afg.ScheduleInstance.generate("swarm")
    with pytest.raises(afg.InvalidInputError, match="speed"):
        afg.ScheduleInstance.parse('{"speed":0,"max_wait":1,"depots":[[0,0]],"robots":[],"tasks":[]}')
    with pytest.raises(afg.MissingFileError):
        afg.ScheduleInstance.read("/no/such/file.jsonl")


def test_a_start_is_searched_on_and_never_lost():
    instances = afg.ScheduleInstance.read(SET / "dcmrta-20a50t.jsonl")
    ctas = published_routes()[0]
    weak = afg.score_schedule(instances[0], ctas)
    better = afg.schedule(instances[0], steps=2000, start=[np.asarray(r) for r in ctas])
    assert better["valid"] and better["makespan"] < weak["makespan"] - 1
    plan = afg.schedule(instances[0], steps=5000, seed=1)
    kept = afg.schedule(instances[0], steps=0, seed=2, start=plan["routes"])
    assert kept["makespan"] <= plan["makespan"]
    with pytest.raises(afg.InvalidInputError, match="task ids start at 0"):
        afg.schedule(instances[0], steps=10, start=[[-1]])

"""The package's API against the crates' own numbers: the committed tables, brute force
through Q*, and clear exceptions for bad input."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

import afg
from afg.gym import AllocationVectorEnv

ROOT = Path(__file__).resolve().parents[3]
RESULTS = ROOT / "docs" / "RESULTS.md"


def table_percent(n: int, label: str) -> float:
    """The % of OPT of `label` in Table I at N = `n` of docs/RESULTS.md."""
    text = RESULTS.read_text()
    block = text[text.index(f"**N = {n}**") :]
    row = re.search(r"^\| " + re.escape(label) + r" \| [^|]+ \| ([0-9.]+) % \|", block, re.M)
    assert row, f"no row {label!r} at N = {n}"
    return float(row.group(1))


@pytest.mark.parametrize(
    "method,label", [("opt", "OPT"), ("da", "GRAPE DA"), ("greedy", "Greedy"), ("nearest", "Nearest")]
)
def test_solve_reproduces_table_one_at_n60(method: str, label: str) -> None:
    instances = afg.read_jsonl(ROOT / "datasets" / "n60.jsonl")[:100]
    percents = [afg.solve(inst, method=method).percent_of_opt for inst in instances]
    assert round(float(np.mean(percents)), 2) == table_percent(60, label)


def test_instances_round_trip_and_expose_numpy_arrays(tmp_path: Path) -> None:
    inst = afg.generate(robots=30, tasks=4, seed=3, capacity_slack=1.2)
    assert inst.robots.shape == (30, 2) and inst.tasks.shape == (4, 2)
    assert inst.rewards.shape == inst.eps.shape == inst.capacities.shape == (4,)
    assert (inst.capacities >= 8).all() and inst.beta == 1.0
    assert afg.generate(robots=30, tasks=4, seed=3, capacity_slack=1.2) == inst
    assert afg.generate(robots=30, tasks=4, seed=4) != inst
    path = tmp_path / "one.json"
    inst.write(path)
    assert afg.Instance.from_json(path) == inst
    assert afg.Instance.parse(inst.to_json()) == inst
    assert afg.Instance.from_dict(inst.to_dict()) == inst
    again = afg.Instance(inst.robots, inst.tasks, inst.rewards, inst.eps, inst.capacities, inst.beta)
    assert again.to_dict()["tasks"] == inst.to_dict()["tasks"]
    afg.write_jsonl(tmp_path / "many.jsonl", [inst, inst])
    assert afg.read_jsonl(tmp_path / "many.jsonl") == [inst, inst]


def test_results_score_what_they_return() -> None:
    inst = afg.generate(robots=40, tasks=5, seed=2)
    res = afg.solve(inst, method="da-balanced")
    assert res.tasks.dtype == np.int64 and res.tasks.shape == (40,)
    assert res.welfare == pytest.approx(inst.welfare(res.tasks))
    assert inst.is_stable(res.tasks, preference="balanced")
    assert res.ns_rate_balanced == inst.ns_rate(res.tasks) == 1.0
    assert afg.score(inst, res.tasks).percent_of_opt == pytest.approx(res.percent_of_opt)
    assert set(res.stats) >= {"iterations", "rounds", "wall_time_s"}
    assert afg.solve(inst, method="opt").welfare == pytest.approx(res.opt_welfare)
    # A list works where an array does.
    assert inst.welfare(res.tasks.tolist()) == res.welfare


def test_trained_models_solve_from_a_path_or_once_loaded() -> None:
    inst = afg.read_jsonl(ROOT / "datasets" / "n60.jsonl")[0]
    model = afg.load_model(ROOT / "models" / "ours" / "price_n60")
    a = model.allocate(inst)
    b = afg.solve(inst, model=str(ROOT / "models" / "ours" / "price_n60"))
    assert (a.tasks == b.tasks).all() and a.percent_of_opt > 95.0
    c = afg.solve(inst, model=model)
    assert (c.tasks == a.tasks).all()


def test_following_argmax_q_star_reaches_the_optimum() -> None:
    for seed in range(20):
        inst = afg.generate(robots=7, tasks=3, seed=seed, capacity_slack=1.0 + (seed % 3) / 2)
        tasks: list = []
        for _ in range(inst.num_robots):
            q = afg.q_star(inst, tasks)
            assert q.shape == (3,)
            tasks.append(int(np.argmax(q)))
        assert inst.welfare(tasks) == pytest.approx(afg.solve(inst, method="opt").welfare)
        # Q* of the empty state is the optimum's welfare.
        assert afg.q_star(inst, []).max() == pytest.approx(inst.welfare(tasks))


def test_reallocation_keeps_survivors_and_settles() -> None:
    old = afg.generate(robots=50, tasks=5, seed=5)
    previous = afg.solve(old, method="opt").tasks
    now = afg.Instance(old.robots[2:], old.tasks, old.rewards, old.eps, None, old.beta)
    res = afg.reallocate(now, previous, left_robots=[0, 1])
    assert res.stats["survivors"] == 48 and res.stats["placed"] == 0
    assert now.is_stable(res.tasks)
    with pytest.raises(ValueError, match="da-balanced"):
        afg.reallocate(now, previous, left_robots=[0, 1], method="greedy")


def test_score_lists_exactly_the_robots_that_would_move() -> None:
    inst = afg.generate(robots=12, tasks=3, seed=4)
    tasks = afg.solve(inst, method="opt").tasks.copy()
    tasks[0] = (tasks[0] + 1) % 3
    card = afg.score(inst, tasks)
    assert card.coalition_sizes.sum() == 12 and card.unassigned == 0
    for pref in ("balanced", "selfish"):
        moves = card.moves(pref)
        assert moves.shape[1] == 3
        assert (moves[:, 1] == tasks[moves[:, 0]]).all()  # each row starts where the robot is
        rate = card.ns_rate_balanced if pref == "balanced" else card.ns_rate_selfish
        assert rate == pytest.approx(1 - len(moves) / 12)
        stable = card.stable_balanced if pref == "balanced" else card.stable_selfish
        assert stable == (len(moves) == 0)
    assert not card.stable_balanced
    with pytest.raises(ValueError, match="unknown preference"):
        card.moves("kind")


def test_grapes_game_lets_robots_stay_out() -> None:
    inst = afg.generate(robots=6, tasks=2, seed=3, allow_void=True)
    assert inst.allow_void and not afg.generate(robots=6, tasks=2, seed=3).allow_void
    again = afg.Instance.parse(inst.to_json())
    assert again.allow_void
    tasks = np.array([0, 1, -1, -1, 0, 1])
    card = afg.score(inst, tasks)
    assert card.unassigned == 2 and card.percent_of_opt <= 100.0 + 1e-9
    opt = afg.solve(inst, method="opt")
    assert afg.score(inst, opt.tasks).percent_of_opt == pytest.approx(100.0)
    for method in ["da", "da-balanced", "greedy", "nearest", "random"]:
        result = afg.solve(inst, method=method)
        assert result.welfare <= opt.welfare + 1e-9
        assert set(result.tasks.tolist()) <= {-1, 0, 1}
    # Far-away robots: the optimum leaves some out.
    far = afg.Instance(
        robots=np.array([[0.0, 0.0], [50.0, 0.0]]),
        tasks=np.array([[0.0, 0.0]]),
        rewards=np.array([1.0]),
        eps=np.array([2.0]),
        allow_void=True,
    )
    assert afg.solve(far, method="opt").tasks.tolist() == [0, -1]
    assert inst.welfare(tasks) == pytest.approx(
        afg.generate(robots=6, tasks=2, seed=3).welfare(tasks)
    )
    paper = afg.generate(robots=6, tasks=2, seed=3)
    with pytest.raises(ValueError, match="robot 2 has no task"):
        afg.score(paper, tasks)


def test_bad_input_raises_with_a_message(tmp_path: Path) -> None:
    inst = afg.generate(robots=10, tasks=3, seed=1)
    with pytest.raises(ValueError, match="unknown method 'nope'"):
        afg.solve(inst, method="nope")
    with pytest.raises(ValueError, match="exactly one"):
        afg.solve(inst)
    with pytest.raises(FileNotFoundError):
        afg.Instance.from_json(tmp_path / "missing.json")
    with pytest.raises(FileNotFoundError):
        afg.load_model(tmp_path / "no-model")
    bad = tmp_path / "bad.jsonl"
    doc = json.loads(inst.to_json())
    doc["tasks"][0]["capcity"] = 2
    bad.write_text(inst.to_json() + "\n" + json.dumps(doc) + "\n")
    with pytest.raises(ValueError, match="line 2.*capcity"):
        afg.read_jsonl(bad)
    with pytest.raises(ValueError, match="shape"):
        afg.Instance(np.zeros((3, 3)), inst.tasks, inst.rewards, inst.eps)
    with pytest.raises(ValueError, match="golden ratio"):
        afg.Instance(inst.robots, inst.tasks, inst.rewards, np.ones(3))
    with pytest.raises(ValueError, match="entries"):
        inst.welfare([0, 1])
    with pytest.raises(ValueError, match="task 7"):
        inst.welfare([7] * 10)
    with pytest.raises(ValueError, match="preference"):
        inst.is_stable([0] * 10, preference="kind")
    with pytest.raises(ValueError, match="no next robot"):
        afg.q_star(inst, [0] * 10)
    with pytest.raises(ValueError, match="index order"):
        afg.q_star(inst, [0, -1, 1])
    # The generator's knobs are checked as `afg gen` checks them, with its message.
    with pytest.raises(ValueError, match=r"capacity slack must be at least 1 \(got 0.5\)"):
        afg.generate(robots=10, tasks=3, capacity_slack=0.5)
    with pytest.raises(ValueError, match='unknown units "metres": expected mean-reward, scale-free or bounded'):
        AllocationVectorEnv(num_envs=1, robots=5, units="metres")
    with pytest.raises(ValueError, match="1e15"):
        afg.Instance(inst.robots * 1e300, inst.tasks, inst.rewards, inst.eps)

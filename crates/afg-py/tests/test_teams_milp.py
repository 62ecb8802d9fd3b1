"""The committed team datasets' certified optima against an independent exact solver:
HiGHS on the textbook MILP (scripts/teams_milp.py) proves the same optimum."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest

import afg

ROOT = Path(__file__).resolve().parents[3]


def milp():
    spec = importlib.util.spec_from_file_location("teams_milp", ROOT / "scripts" / "teams_milp.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("game", ["thresholds", "skills", "both"])
def test_highs_proves_the_committed_optima_of_the_small_team_games(game: str) -> None:
    pytest.importorskip("highspy")
    lines = (ROOT / "datasets" / f"teams-{game}.jsonl").read_text().splitlines()
    optima = json.loads((ROOT / "datasets" / f"teams-{game}.optima.json").read_text())
    highs = milp().highs
    checked = 0
    for line, optimum in zip(lines, optima):
        if optimum["robots"] > 20:
            continue
        solved = highs(json.loads(line), time_limit=60.0, threads=1)
        assert solved["status"] == "optimal"
        welfare = afg.Instance.parse(line).welfare(solved["tasks"])
        assert optimum["proven"] and optimum["welfare"] == optimum["bound"]
        assert welfare == pytest.approx(optimum["welfare"], rel=1e-9, abs=1e-9)
        assert solved["bound"] == pytest.approx(optimum["welfare"], rel=1e-6)
        checked += 1
    assert checked == 10

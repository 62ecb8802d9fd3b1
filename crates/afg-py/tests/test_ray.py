"""The Ray study example: a small grid as Ray tasks on a local Ray instance gives the
serial run's results (skipped where Ray is not installed)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

ray = pytest.importorskip("ray")

EXAMPLE = Path(__file__).resolve().parents[3] / "examples" / "python" / "ray_study.py"


def test_the_ray_study_gives_the_serial_results() -> None:
    spec = importlib.util.spec_from_file_location("ray_study", EXAMPLE)
    assert spec is not None and spec.loader is not None
    study = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(study)
    cells = study.grid(["waves", "attrition"], 2, ["opt", "greedy"])
    assert len(cells) == 2 * 2 * 2 * 2
    ray.init(num_cpus=2, include_dashboard=False)
    try:
        distributed = study.on_ray(cells, 40, 12)
    finally:
        ray.shutdown()
    alone = study.serial(cells, 40, 12)
    assert len(distributed) == len(alone) == len(cells)
    assert all(study.same(a, b) for a, b in zip(distributed, alone))
    # Not every cell is alike: the comparison can fail.
    assert not all(study.same(alone[0], b) for b in alone[1:])
    assert "| waves | greedy (warm) |" in study.table(cells, distributed)

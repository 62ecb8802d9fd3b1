"""Missions from Python: drawn, written and read back; run with allocators in the loop."""

from __future__ import annotations

import inspect
import json
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

import afg

ROOT = Path(__file__).resolve().parents[3]


def test_missions_round_trip_and_show_their_arrays(tmp_path: Path) -> None:
    mission = afg.Mission.generate("waves", robots=20, tasks=8, seed=3)
    assert (mission.num_robots, mission.num_tasks, mission.horizon) == (20, 8, 40.0)
    assert mission.robot_positions.shape == (20, 2) and mission.task_positions.shape == (8, 2)
    assert sorted(set(mission.appears.tolist())) == [0.0, 5.0, 10.0, 15.0]
    assert ((1.0 <= mission.workloads) & (mission.workloads <= 3.0)).all()
    path = tmp_path / "m.json"
    mission.write(path)
    assert afg.Mission.from_json(path) == mission == afg.Mission.parse(mission.to_json())
    assert afg.Mission.generate("waves", robots=20, tasks=8, seed=4) != mission


def test_run_mission_gives_metrics_timeline_and_decisions() -> None:
    mission = afg.Mission.generate("attrition", robots=30, tasks=6, seed=1)
    res = afg.run_mission(mission, method="greedy", trace=True)
    m = res.metrics
    # The metrics are the trace's: the tasks it reports done, and their r_j W_j.
    events = [json.loads(line) for line in res.trace_jsonl().splitlines()]
    done = [e["task"] for e in events if e["event"] == "task_done"]
    tasks = json.loads(mission.to_json())["tasks"]
    assert m["tasks"] == 6 and m["tasks_done"] == len(done) == len(set(done)) > 0
    worth = sum(tasks[j]["reward"] * tasks[j]["workload"] for j in done)
    assert m["reward_done"] == pytest.approx(worth, rel=1e-12)
    assert m["reward_done"] <= m["reward_total"] + 1e-9
    t = res.timeline
    assert (np.diff(t["time"]) >= 0).all() and (np.diff(t["done"]) >= 0).all()
    times, tasks = res.decisions
    assert tasks.shape == (len(times), 30) and len(times) == m["decisions"]
    assert tasks.min() >= -1 and tasks.max() < 6
    assert '"event":"decision"' in res.trace_jsonl()
    # The same seed, the same run; the incremental optimum, the same optimum's outcome.
    again = afg.run_mission(mission, method="greedy", trace=True)
    assert (again.decisions[1] == tasks).all()
    opt = afg.run_mission(mission, method="opt")
    warm = afg.run_mission(mission, method="opt", warm=True)
    assert warm.metrics["tasks_done"] == opt.metrics["tasks_done"]
    late = afg.run_mission(mission, method="opt", latency=0.5, trace=True)
    decisions = [e for e in map(json.loads, late.trace_jsonl().splitlines()) if e["event"] == "decision"]
    assert len(decisions) == len(late.decisions[0]) > 0
    # Each decision lands exactly 0.5 after it was asked for, the first at 0.5.
    assert late.decisions[0][0] == 0.5
    assert all(d["time"] - d["asked"] == pytest.approx(0.5, abs=1e-12) for d in decisions)


def test_grape_runs_over_the_radio_inside_a_mission() -> None:
    mission = afg.Mission.generate("waves", robots=30, tasks=6, seed=2)
    res = afg.run_mission(mission, method="grape", radius=0.5, loss=0.2, seed=1, trace=True)
    swarm = res.metrics["swarm"]
    assert swarm["robots"] == 30 and swarm["rounds"] == res.metrics["decisions"] > 0
    assert swarm["messages"] > 0 and swarm["bytes"] > 0
    again = afg.run_mission(mission, method="grape", radius=0.5, loss=0.2, seed=1, trace=True)
    assert (again.decisions[1] == res.decisions[1]).all()
    assert "swarm" not in afg.run_mission(mission, method="greedy").metrics
    auction = afg.run_mission(mission, method="auction", radius=0.5).metrics
    assert auction["tasks"] == 6 and auction["swarm"]["rounds"] > 0
    with pytest.raises(ValueError, match="decentralised"):
        afg.run_mission(mission, method="grape", latency=1.0)
    with pytest.raises(ValueError, match="loss"):
        afg.run_mission(mission, method="grape", loss=1.5)


def test_bad_missions_and_options_raise_with_a_message(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="unknown preset"):
        afg.Mission.generate("storm", robots=5, tasks=2)
    mission = afg.Mission.generate("static", robots=5, tasks=2)
    with pytest.raises(ValueError, match="speed"):
        afg.Mission.parse(mission.to_json().replace('"speed":1.0', '"speed":-2.0', 1))
    with pytest.raises(FileNotFoundError):
        afg.Mission.from_json(tmp_path / "none.json")
    with pytest.raises(ValueError, match="unknown method"):
        afg.run_mission(mission, method="oracle")
    with pytest.raises(ValueError, match="not both"):
        afg.run_mission(mission, latency=1.0, latency_factor=2.0)


def _welfare_of_greedy(instance: afg.Instance) -> float:
    return afg.solve(instance, method="greedy").welfare


def test_every_object_pickles_and_crosses_processes() -> None:
    import multiprocessing
    import pickle

    inst = afg.generate(robots=12, tasks=3, seed=5, allow_void=True)
    mission = afg.Mission.generate("poisson", robots=10, tasks=4, seed=2)
    model = afg.load_model(ROOT / "models" / "ours" / "price_n60", one_shot=True)
    assert pickle.loads(pickle.dumps(inst)) == inst
    assert pickle.loads(pickle.dumps(mission)) == mission
    again = pickle.loads(pickle.dumps(model))
    assert (again.allocate(inst).tasks == model.allocate(inst).tasks).all()
    result = afg.solve(inst, method="da")
    back = pickle.loads(pickle.dumps(result))
    assert (back.tasks == result.tasks).all() and back.stats == result.stats
    assert (back.welfare, back.percent_of_opt, back.coalition_sizes.tolist()) == (
        result.welfare, result.percent_of_opt, result.coalition_sizes.tolist()
    )
    assert (back.moves("selfish") == result.moves("selfish")).all()
    run = afg.run_mission(mission, method="greedy", trace=True)
    again = pickle.loads(pickle.dumps(run))
    assert again.metrics == run.metrics and again.trace_jsonl() == run.trace_jsonl()
    assert (again.timeline["time"] == run.timeline["time"]).all()
    instances = [afg.generate(robots=20, tasks=4, seed=s) for s in range(3)]
    with multiprocessing.get_context("spawn").Pool(2) as pool:
        far = pool.map(_welfare_of_greedy, instances)
    assert far == [_welfare_of_greedy(i) for i in instances]


def _cli_help(*command: str) -> str:
    """`afg <command> --help`, from the workspace's build (built by cargo if missing)."""
    binary = ROOT / "target" / "release" / "afg"
    if binary.exists():
        args = [str(binary), *command, "--help"]
    else:
        args = ["cargo", "run", "--release", "--quiet", "--package", "afg-cli", "--", *command, "--help"]
    return subprocess.run(args, cwd=ROOT, check=True, capture_output=True, text=True).stdout


def _flags(*command: str) -> dict:
    """Every `--flag` of `afg <command> --help` with its default as shown (or None)."""
    flags: dict = {}
    flag = None
    for line in _cli_help(*command).splitlines():
        named = re.match(r"^\s+(?:-\w, )?--([a-z-]+)", line)
        if named:
            flag = named.group(1)
            flags[flag] = None
        shown = re.search(r"\[default: ([^\]]+)\]", line)
        if shown and flag is not None and flags[flag] is None:
            flags[flag] = shown.group(1)
    flags.pop("help")
    return flags


def _same_knobs(flags: dict, function, defaults: dict, cli_only: set) -> None:
    """`function` takes every flag (but `cli_only`) under its Python name, and those
    left at None default to what the command line shows."""
    names = {f.replace("-", "_") for f in flags} - cli_only
    params = inspect.signature(function).parameters
    assert names == set(params) - {"self"}, (names ^ set(params))
    for name, value in defaults.items():
        assert params[name].default is None, name
        shown = flags[name.replace("_", "-")]
        if value is None:
            # No default value, or one the help describes in words.
            assert shown is None or re.fullmatch(r"[a-z ]+", shown), (name, shown)
        elif isinstance(value, tuple):
            assert shown == ",".join(f"{v:g}" for v in value), (name, shown, value)
        else:
            assert shown == str(value) or float(shown) == float(value), (name, shown, value)


def test_run_mission_takes_every_knob_of_the_command_line_with_its_default() -> None:
    flags = _flags("mission", "run")
    assert {"mission", "method", "loss", "activation", "knn", "trace"} <= set(flags), flags
    # What only a command line has: its output files and format (the animation and its
    # stills; Python draws a moment with MissionEnv.render). `trace` is a path there
    # and a switch in Python.
    cli_only = {"json", "animate", "still", "still_at"}
    _same_knobs(flags, afg.run_mission, afg.mission_defaults()["run"], cli_only)


def test_mission_generate_takes_every_knob_of_the_command_line_with_its_default() -> None:
    flags = _flags("mission", "gen")
    assert {"preset", "robots", "workload", "fail-share"} <= set(flags), flags
    _same_knobs(flags, afg.Mission.generate, afg.mission_defaults()["generate"], {"out"})


def test_a_radio_knob_with_a_central_method_is_refused() -> None:
    mission = afg.Mission.generate("waves", robots=10, tasks=3, seed=1)
    for knob in (dict(loss=0.3), dict(radius=0.2), dict(preference="balanced"), dict(knn=4)):
        with pytest.raises(afg.InvalidInputError, match="for grape and auction"):
            afg.run_mission(mission, method="greedy", **knob)
    # The same knobs with GRAPE run, and change its run.
    plain = afg.run_mission(mission, method="grape", seed=1).metrics
    lossy = afg.run_mission(mission, method="grape", seed=1, loss=0.5, knn=2).metrics
    assert plain["swarm"]["messages"] != lossy["swarm"]["messages"]


def test_errors_are_afg_errors_and_the_builtin_kinds(tmp_path: Path) -> None:
    assert issubclass(afg.InvalidInputError, ValueError) and issubclass(afg.InvalidInputError, afg.AfgError)
    assert issubclass(afg.MissingFileError, FileNotFoundError) and issubclass(afg.MissingFileError, afg.AfgError)
    assert issubclass(afg.RefusedError, RuntimeError) and issubclass(afg.RefusedError, afg.AfgError)
    with pytest.raises(afg.MissingFileError):
        afg.Mission.from_json(tmp_path / "none.json")
    with pytest.raises(afg.MissingFileError):
        afg.read_jsonl(tmp_path / "none.jsonl")
    with pytest.raises(afg.MissingFileError):
        afg.load_model(tmp_path / "no-run")
    with pytest.raises(afg.InvalidInputError, match="unknown preset"):
        afg.Mission.generate("storm", robots=5, tasks=2)
    with pytest.raises(afg.InvalidInputError):
        afg.generate(robots=0, tasks=2)
    with pytest.raises(afg.InvalidInputError):
        afg.solve(afg.generate(robots=5, tasks=2), method="oracle")


def _cli(*args: str) -> str:
    """`afg <args>`'s standard output, from the workspace's build (built if missing)."""
    binary = ROOT / "target" / "release" / "afg"
    command = [str(binary)] if binary.exists() else ["cargo", "run", "--release", "--quiet", "--package", "afg-cli", "--"]
    return subprocess.run([*command, *args], cwd=ROOT, check=True, capture_output=True, text=True).stdout


def test_python_and_the_command_line_run_the_same_mission_alike(tmp_path: Path) -> None:
    mission = afg.Mission.generate("attrition", robots=25, tasks=6, seed=7, capacity_slack=1.2)
    path = tmp_path / "m.json"
    mission.write(path)
    timing = {"compute_mean_s", "compute_max_s", "compute_total_s"}
    for flags, kwargs in [
        (["--method", "greedy"], dict(method="greedy")),
        (["--method", "opt", "--warm", "--latency", "0.25"], dict(method="opt", warm=True, latency=0.25)),
        (["--method", "grape", "--loss", "0.3", "--knn", "4", "--seed", "2"], dict(method="grape", loss=0.3, knn=4, seed=2)),
    ]:
        cli = json.loads(_cli("mission", "run", "--mission", str(path), "--json", *flags))
        ours = afg.run_mission(mission, **kwargs).metrics
        assert set(cli) == set(ours), flags
        for key in set(cli) - timing:
            assert ours[key] == cli[key], (flags, key, ours[key], cli[key])

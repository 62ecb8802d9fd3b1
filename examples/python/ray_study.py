"""A mission study grid — presets × seeds × methods — run as Ray tasks.

On a local Ray instance by default; on a cluster unchanged, by ``--address`` or the
``RAY_ADDRESS`` environment variable (``ray.init`` reads it). Missions travel to the
workers pickled (``afg.Mission`` pickles through its JSON document); each task runs one
mission with one method and returns its metrics. The script runs the same grid
serially too and checks that every result is the same (compute times aside, which are
the machine's).

    pip install ray
    python examples/python/ray_study.py [--robots 1000] [--tasks 100] [--seeds 4]
    RAY_ADDRESS=ray://head:10001 python examples/python/ray_study.py   # on a cluster
"""

from __future__ import annotations

import argparse
import time
from typing import Dict, List, Optional, Sequence, Tuple

import afg

#: (preset, seed, method, warm): one run of the grid.
Cell = Tuple[str, int, str, bool]

#: Metrics that are the machine's, not the run's.
TIMINGS = ("compute_mean_s", "compute_max_s", "compute_total_s")


def grid(presets: Sequence[str], seeds: int, methods: Sequence[str]) -> List[Cell]:
    """Every preset × seed × method, each method from scratch and warm-started."""
    return [
        (preset, seed, method, warm)
        for preset in presets
        for seed in range(seeds)
        for method in methods
        for warm in (False, True)
    ]


def run_cell(mission: afg.Mission, method: str, warm: bool) -> Dict[str, object]:
    """One mission with one method: its metrics."""
    return afg.run_mission(mission, method=method, warm=warm).metrics


def missions(cells: Sequence[Cell], robots: int, tasks: int) -> Dict[Tuple[str, int], afg.Mission]:
    """The grid's missions, each drawn once."""
    keys = sorted({(preset, seed) for preset, seed, _, _ in cells})
    return {(p, s): afg.Mission.generate(p, robots=robots, tasks=tasks, seed=s) for p, s in keys}


def serial(cells: Sequence[Cell], robots: int, tasks: int) -> List[Dict[str, object]]:
    drawn = missions(cells, robots, tasks)
    return [run_cell(drawn[(p, s)], m, w) for p, s, m, w in cells]


def on_ray(cells: Sequence[Cell], robots: int, tasks: int) -> List[Dict[str, object]]:
    """The grid as Ray tasks (Ray must be initialised); results in the grid's order."""
    import ray

    remote = ray.remote(run_cell)
    drawn = {key: ray.put(m) for key, m in missions(cells, robots, tasks).items()}
    return ray.get([remote.remote(drawn[(p, s)], m, w) for p, s, m, w in cells])


def same(a: Dict[str, object], b: Dict[str, object]) -> bool:
    """Equal metrics, the timings aside."""
    return {k: v for k, v in a.items() if k not in TIMINGS} == {
        k: v for k, v in b.items() if k not in TIMINGS
    }


def table(cells: Sequence[Cell], results: Sequence[Dict[str, object]]) -> str:
    """Means per preset and method: tasks done, reward done, mean task latency."""
    rows: Dict[Tuple[str, str], List[Dict[str, object]]] = {}
    for (preset, _, method, warm), metrics in zip(cells, results):
        rows.setdefault((preset, method + (" (warm)" if warm else "")), []).append(metrics)
    out = ["| preset | method | tasks done | reward done, % | latency mean |", "|---|---|---|---|---|"]
    for (preset, method), ms in rows.items():
        done = sum(float(m["tasks_done"]) for m in ms) / len(ms)
        share = sum(100 * float(m["reward_done"]) / float(m["reward_total"]) for m in ms) / len(ms)
        latency = sum(float(m["latency_mean"] or 0.0) for m in ms) / len(ms)
        out.append(f"| {preset} | {method} | {done:.2f} | {share:.2f} | {latency:.3f} |")
    return "\n".join(out)


def main(argv: Optional[Sequence[str]] = None) -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--robots", type=int, default=1000)
    parser.add_argument("--tasks", type=int, default=100)
    parser.add_argument("--seeds", type=int, default=4)
    parser.add_argument("--presets", default="waves,poisson,attrition")
    parser.add_argument("--methods", default="opt,da,greedy")
    parser.add_argument("--address", default=None, help="a Ray cluster (default: RAY_ADDRESS, else a local instance)")
    args = parser.parse_args(argv)
    import ray

    cells = grid(args.presets.split(","), args.seeds, args.methods.split(","))
    start = time.perf_counter()
    ray.init(address=args.address)
    init_s = time.perf_counter() - start
    started = time.perf_counter()
    distributed = on_ray(cells, args.robots, args.tasks)
    on_ray_s = time.perf_counter() - started
    resources = ray.cluster_resources()
    ray.shutdown()
    started = time.perf_counter()
    alone = serial(cells, args.robots, args.tasks)
    serial_s = time.perf_counter() - started
    identical = all(same(a, b) for a, b in zip(distributed, alone))
    print(table(cells, distributed))
    print(
        f"\n{len(cells)} runs on Ray ({resources.get('CPU', 0):.0f} CPUs) in {on_ray_s:.1f} s "
        f"(Ray started in {init_s:.1f} s), serially in {serial_s:.1f} s; "
        f"results identical to the serial run: {'yes' if identical else 'NO'}"
    )
    if not identical:
        raise SystemExit(1)


if __name__ == "__main__":
    main()

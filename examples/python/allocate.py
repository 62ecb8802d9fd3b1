"""Allocate your own robots: read an instance file (or draw one), solve it by several
methods against the exact optimum, write the assignment, and draw the map with
matplotlib if it is installed.

    python examples/python/allocate.py [mine.json] [--plot map.png]
"""

import argparse

import afg

parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
parser.add_argument("instance", nargs="?", help="an afg-instance JSON file (default: draw N = 200, M = 8)")
parser.add_argument("--plot", help="write the OPT assignment as a picture (needs matplotlib)")
args = parser.parse_args()

inst = afg.Instance.from_json(args.instance) if args.instance else afg.generate(robots=200, tasks=8, seed=1)
print(f"{inst.num_robots} robots, {inst.num_tasks} tasks")
for method in ["opt", "da-balanced", "da", "greedy", "nearest"]:
    res = afg.solve(inst, method=method)
    print(
        f"{method:12s} welfare {res.welfare:9.3f}  {res.percent_of_opt:7.2f} % of OPT  "
        f"NS_rate balanced {100 * res.ns_rate_balanced:5.1f} %  {1e3 * res.stats['wall_time_s']:8.3f} ms"
    )

best = afg.solve(inst, method="opt")
# The optimum is the optimum: no method scores above it, and it scores 100 %.
if best.percent_of_opt != 100.0 or any(
    afg.solve(inst, method=m).welfare > best.welfare + 1e-9 for m in ["da-balanced", "da", "greedy", "nearest"]
):
    raise SystemExit("a method scored above the exact optimum")
if args.plot:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise SystemExit("--plot needs matplotlib: pip install matplotlib")
    robots, tasks = inst.robots, inst.tasks
    fig, ax = plt.subplots(figsize=(5, 5))
    ax.scatter(robots[:, 0], robots[:, 1], c=best.tasks, cmap="tab10", s=12)
    ax.scatter(tasks[:, 0], tasks[:, 1], c=range(inst.num_tasks), cmap="tab10", marker="*", s=300, edgecolors="k")
    ax.set_title(f"OPT, welfare {best.welfare:.2f}")
    fig.savefig(args.plot, dpi=120)
    print(f"map in {args.plot}")

"""The exact optimum of afg instances with OR-Tools' SimpleMinCostFlow, for
`cargo xtask bench-opt` to time against afg's own solver on the same files.

The textbook network: source -> robot (capacity 1) -> task (capacity 1, cost beta d)
-> sink through one arc per member slot k = 1..min(capacity, N) (capacity 1, cost
C - (F_j(k) - F_j(k-1)) for a constant C >= every marginal value, which shifts the
objective by N C and keeps every cost non-negative). Costs are rounded to integers after
scaling by 1e9, or less where OR-Tools' cost-scaling could overflow 64 bits; the
assignment comes back to afg, which computes its welfare exactly.

Only `solve()` is timed (best of --repeats, each on a freshly built network).

Usage: python scripts/ortools_opt.py INSTANCES.jsonl OUT.json [--repeats K]
Needs: pip install ortools numpy
"""

import argparse
import json
import math
import time

import numpy as np
from ortools.graph.python import min_cost_flow

MAX_SCALE = 1e9
# OR-Tools' cost scaling multiplies costs by about the node count: keep the product
# below 2^62.
COST_LIMIT = 2.0**62


def marginal_values(task, count):
    """F_j(k) - F_j(k-1) for k = 1..count, as afg's Instance::marginal_value."""
    k = np.arange(1, count + 1, dtype=np.float64)
    eps, reward = task["eps"], task["reward"]
    with np.errstate(divide="ignore"):
        v = reward * np.log1p(1.0 / (k + eps - 2.0)) / math.log(eps)
    v[0] = reward
    return v


def network(instance):
    """Arrays (tails, heads, capacities, real costs) and node counts of the network."""
    robots = np.array([[r["x"], r["y"]] for r in instance["robots"]], dtype=np.float64)
    tasks = instance["tasks"]
    n, m = len(robots), len(tasks)
    source, first_task, sink = n, n + 1, n + 1 + m
    positions = np.array([[t["position"]["x"], t["position"]["y"]] for t in tasks])
    cost = instance["beta"] * np.hypot(
        robots[:, None, 0] - positions[None, :, 0], robots[:, None, 1] - positions[None, :, 1]
    )
    slots = [marginal_values(t, min(t.get("capacity") or n, n)) for t in tasks]
    top = max(float(s.max()) for s in slots)
    tails = [np.full(n, source), np.repeat(np.arange(n), m)]
    heads = [np.arange(n), np.tile(np.arange(first_task, first_task + m), n)]
    costs = [np.zeros(n), cost.ravel()]
    for j, s in enumerate(slots):
        tails.append(np.full(len(s), first_task + j))
        heads.append(np.full(len(s), sink))
        costs.append(top - s)
    tails, heads, costs = (np.concatenate(a) for a in (tails, heads, costs))
    return tails, heads, costs, n, m, sink


def solve_once(tails, heads, unit_costs, n, m, sink):
    """Builds the network (not timed), solves it (timed): (status, seconds, assignment)."""
    smcf = min_cost_flow.SimpleMinCostFlow()
    arcs = smcf.add_arcs_with_capacity_and_unit_cost(
        tails.astype(np.int32), heads.astype(np.int32), np.ones(len(tails), np.int64), unit_costs
    )
    smcf.set_nodes_supplies(np.array([n, sink], np.int32), np.array([n, -n], np.int64))
    start = time.perf_counter()
    status = smcf.solve()
    elapsed = time.perf_counter() - start
    if status != smcf.OPTIMAL:
        return status, elapsed, None
    flows = smcf.flows(arcs[n : n + n * m])
    return status, elapsed, np.argmax(flows.reshape(n, m), axis=1)


def solve(instance, repeats):
    tails, heads, costs, n, m, sink = network(instance)
    nodes = sink + 1
    scale = min(MAX_SCALE, COST_LIMIT / (nodes * max(float(costs.max()), 1e-300)))
    best, assignment = math.inf, None
    while assignment is None:
        unit_costs = np.rint(costs * scale).astype(np.int64)
        status, elapsed, assignment = solve_once(tails, heads, unit_costs, n, m, sink)
        if assignment is None:
            if "BAD_COST_RANGE" not in str(status) or scale < 1.0:
                raise SystemExit(f"OR-Tools status {status} (not OPTIMAL)")
            # OR-Tools' own overflow check is stricter than the bound above.
            scale /= 16.0
    best = elapsed
    for _ in range(repeats - 1):
        _, elapsed, _ = solve_once(tails, heads, unit_costs, n, m, sink)
        best = min(best, elapsed)
    return {"seconds": best, "scale": scale, "tasks": assignment.tolist()}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("instances")
    parser.add_argument("out")
    parser.add_argument("--repeats", type=int, default=1)
    args = parser.parse_args()
    with open(args.instances) as f:
        results = [solve(json.loads(line), args.repeats) for line in f if line.strip()]
    with open(args.out, "w") as f:
        json.dump(results, f)


if __name__ == "__main__":
    main()

"""Schedules of afg's scheduling instances with OR-Tools CP-SAT, for
`cargo xtask bench-schedule` to set beside afg's scheduler on the same files.

The interval-style model of the problem (times in thousandths, travel and durations
rounded up, so every schedule it finds is one the robots can keep):

    x_ij = 1 when robot i is in task j's team; sum_i x_ij = min_team_j, or with
           skills sum_i q_is x_ij >= R_js (and at least one robot);
    per robot, a circuit through its depot (node 0) and the tasks it joins
           (AddCircuit; a task it does not join is skipped by a self-loop on not x_ij);
    an arc a -> b of robot i:  S_b >= S_a + D_a + T_ab          (it arrives in time)
                               S_b <= S_a + D_a + T_ab + W      (waits at most max_wait);
    from the depot:            T_0b <= S_b <= T_0b + W;
    into the depot:            C >= S_a + D_a + T_a0;
    minimise C (the makespan).

The routes come back to afg, whose evaluator replays them under the instance's rules:
the makespan reported is the evaluator's, and a schedule whose replay breaks max_wait
is reported as invalid. The bound is CP-SAT's (null before its first solution).

Usage: python scripts/schedule_cpsat.py INSTANCES.jsonl LINE OUT.json --time-limit S
           [--workers K] [--max-wait W]
Needs: pip install ortools
"""

import argparse
import json
import math
import time

SCALE = 1000


def ceil_time(x):
    return int(math.ceil(x * SCALE - 1e-9))


def model(inst, max_wait):
    from ortools.sat.python import cp_model

    robots, tasks, speed = inst["robots"], inst["tasks"], inst["speed"]
    n, m = len(robots), len(tasks)
    skills = inst.get("skills") or 0
    depots = inst["depots"]

    def dist(p, q):
        return math.hypot(p[0] - q[0], p[1] - q[1])

    pos = [(t["x"], t["y"]) for t in tasks]
    dur = [ceil_time(t["duration"]) for t in tasks]
    travel = [[ceil_time(dist(pos[a], pos[b]) / speed) for b in range(m)] for a in range(m)]
    wait = int(math.floor(max_wait * SCALE))
    horizon = sum(dur) + sum(max(row) for row in travel) + 2 * ceil_time(2 ** 0.5 / speed) * m + wait * m

    cp = cp_model.CpModel()
    start = [cp.NewIntVar(0, horizon, f"S{j}") for j in range(m)]
    makespan = cp.NewIntVar(0, horizon, "C")
    x = [[cp.NewBoolVar(f"x{i}_{j}") for j in range(m)] for i in range(n)]
    for j, t in enumerate(tasks):
        column = [x[i][j] for i in range(n)]
        if t.get("requires") is not None:
            cp.Add(sum(column) >= max(1, t.get("min_team") or 1))
            for s in range(skills):
                need = t["requires"][s]
                if need > 0:
                    cp.Add(sum(robots[i]["skills"][s] * x[i][j] for i in range(n)) >= need)
        else:
            cp.Add(sum(column) == t["min_team"])
    routes = []
    for i, r in enumerate(robots):
        home = depots[r["depot"]]
        out0 = [ceil_time(dist((r["x"], r["y"]), pos[b]) / speed) for b in range(m)]
        back = [ceil_time(dist(pos[a], home) / speed) for a in range(m)]
        arcs, lits = [], {}
        idle = cp.NewBoolVar(f"idle{i}")
        arcs.append((0, 0, idle))
        cp.Add(sum(x[i]) == 0).OnlyEnforceIf(idle)
        for b in range(m):
            arcs.append((b + 1, b + 1, x[i][b].Not()))
            lit = cp.NewBoolVar("")
            arcs.append((0, b + 1, lit))
            cp.Add(start[b] >= out0[b]).OnlyEnforceIf(lit)
            cp.Add(start[b] <= out0[b] + wait).OnlyEnforceIf(lit)
            lits[(0, b + 1)] = lit
            lit = cp.NewBoolVar("")
            arcs.append((b + 1, 0, lit))
            cp.Add(makespan >= start[b] + dur[b] + back[b]).OnlyEnforceIf(lit)
            lits[(b + 1, 0)] = lit
            for a in range(m):
                if a != b:
                    lit = cp.NewBoolVar("")
                    arcs.append((a + 1, b + 1, lit))
                    arrive = start[a] + dur[a] + travel[a][b]
                    cp.Add(start[b] >= arrive).OnlyEnforceIf(lit)
                    cp.Add(start[b] <= arrive + wait).OnlyEnforceIf(lit)
                    lits[(a + 1, b + 1)] = lit
        cp.AddCircuit(arcs)
        routes.append(lits)
    cp.Minimize(makespan)
    return cp, routes, m


def follow(solver, lits, m):
    nxt = {a: b for (a, b), lit in lits.items() if solver.Value(lit)}
    route, here = [], 0
    while here in nxt and nxt[here] != 0 and len(route) <= m:
        here = nxt[here]
        route.append(here - 1)
    return route


def main():
    from ortools.sat.python import cp_model

    p = argparse.ArgumentParser()
    p.add_argument("instances")
    p.add_argument("line", type=int)
    p.add_argument("out")
    p.add_argument("--time-limit", type=float, required=True)
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--max-wait", type=float, default=None)
    a = p.parse_args()
    with open(a.instances) as f:
        inst = [json.loads(l) for l in f if l.strip()][a.line]
    clock = time.time()
    cp, routes, m = model(inst, a.max_wait if a.max_wait is not None else inst["max_wait"])
    solver = cp_model.CpSolver()
    solver.parameters.max_time_in_seconds = a.time_limit
    solver.parameters.num_workers = a.workers
    status = solver.Solve(cp)
    found = status in (cp_model.OPTIMAL, cp_model.FEASIBLE)
    result = {
        "status": solver.StatusName(status),
        "seconds": time.time() - clock,
        "bound": solver.BestObjectiveBound() / SCALE if found else None,
        "routes": [follow(solver, lits, m) for lits in routes] if found else None,
    }
    with open(a.out, "w") as f:
        json.dump(result, f)


if __name__ == "__main__":
    main()

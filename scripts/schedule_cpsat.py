"""Schedules of afg's scheduling instances with OR-Tools CP-SAT, for
`cargo xtask bench-schedule` to set beside afg's scheduler on the same files.

A flow model of the problem (times in thousandths, travel and durations rounded up).
Robots that start at the same
place, return to the same depot and hold the same skills are interchangeable: they form
a kind g of c_g robots (DCMRTA's set: one kind of 20), and the model counts how many
robots of each kind take each step instead of naming them:

    z_gj = robots of kind g in task j's team; sum_g z_gj = min_team_j, or with skills
           sum_g q_gs z_gj >= R_js (and at least one robot);
    y_gab = robots of kind g that go from a to b (a: g's start or a task, b: a task or
           g's depot); into each task as many as its team holds of g, out as many;
           at most c_g leave the start, as many come home;
    u_ab = 1 when any robot goes from task a to task b (y_gab <= c_g u_ab), and then
           S_b >= S_a + D_a + T_ab          (it arrives in time)
           S_b <= S_a + D_a + T_ab + W      (waits at most max_wait);
    from g's start to b:  T_0b <= S_b <= T_0b + W;   into g's depot:  C >= S_a + D_a + T_a0;
    minimise C (the makespan).

Times rise along every step, so no flow can go round a cycle, and the flow splits into
one route per robot: the model is exact, and as small as the kinds allow (DCMRTA's
set: 2 550 steps, against 52 000 arcs for a circuit per robot).

The routes come back to afg, whose evaluator replays them under the instance's rules:
the makespan reported is the evaluator's. The model lets a task start after its last
member arrives, the robots start it at once; where that moves a later wait past
max_wait (a waiting margin of 2 thousandths a step covers only the rounding), the
replay reports the schedule as invalid. (Forcing every start onto its last arrival
left CP-SAT without any schedule in 60 s on DCMRTA's instance 0.) The bound is CP-SAT's (null before its first solution).

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


def kinds(robots, skills):
    """Robots grouped by (start, depot, skills), in order of first appearance."""
    groups = {}
    for i, r in enumerate(robots):
        key = (r["x"], r["y"], r["depot"], tuple(r.get("skills") or [0] * skills))
        groups.setdefault(key, []).append(i)
    return list(groups.items())


def model(inst, max_wait):
    from ortools.sat.python import cp_model

    robots, tasks, speed = inst["robots"], inst["tasks"], inst["speed"]
    m = len(tasks)
    skills = inst.get("skills") or 0
    depots = inst["depots"]

    def dist(p, q):
        return math.hypot(p[0] - q[0], p[1] - q[1])

    pos = [(t["x"], t["y"]) for t in tasks]
    dur = [ceil_time(t["duration"]) for t in tasks]
    travel = [[ceil_time(dist(pos[a], pos[b]) / speed) for b in range(m)] for a in range(m)]
    # Rounding up moves a replayed time by at most a thousandth a step: keep that much
    # of max_wait back for every step a route can take.
    wait = int(math.floor(max_wait * SCALE)) - 2 * (m + 1)
    horizon = sum(dur) + sum(max(row) for row in travel) + 2 * ceil_time(2 ** 0.5 / speed) * m + wait * m

    cp = cp_model.CpModel()
    start = [cp.NewIntVar(0, horizon, f"S{j}") for j in range(m)]
    makespan = cp.NewIntVar(0, horizon, "C")
    used = {}

    def step_into(b, lit, arrive):
        cp.Add(start[b] >= arrive).OnlyEnforceIf(lit)
        cp.Add(start[b] <= arrive + wait).OnlyEnforceIf(lit)

    for a in range(m):
        for b in range(m):
            if a != b:
                used[(a, b)] = cp.NewBoolVar(f"u{a}_{b}")
                step_into(b, used[(a, b)], start[a] + dur[a] + travel[a][b])
    groups = kinds(robots, skills)
    team = [[] for _ in range(m)]
    flows = []
    for g, ((x, y, depot, held), members) in enumerate(groups):
        c = len(members)
        home = depots[depot]
        z = [cp.NewIntVar(0, c, f"z{g}_{j}") for j in range(m)]
        for j in range(m):
            team[j].append((held, z[j]))
        steps = {}
        for b in range(m):
            flow = cp.NewIntVar(0, c, "")
            lit = cp.NewBoolVar("")
            cp.Add(flow <= c * lit)
            step_into(b, lit, ceil_time(dist((x, y), pos[b]) / speed))
            steps[("start", b)] = flow
            flow = cp.NewIntVar(0, c, "")
            lit = cp.NewBoolVar("")
            cp.Add(flow <= c * lit)
            back = ceil_time(dist(pos[b], home) / speed)
            cp.Add(makespan >= start[b] + dur[b] + back).OnlyEnforceIf(lit)
            steps[(b, "home")] = flow
            for a in range(m):
                if a != b:
                    flow = cp.NewIntVar(0, c, "")
                    cp.Add(flow <= c * used[(a, b)])
                    steps[(a, b)] = flow
        for j in range(m):
            cp.Add(sum(f for (a, b), f in steps.items() if b == j) == z[j])
            cp.Add(sum(f for (a, b), f in steps.items() if a == j) == z[j])
        leave = sum(steps[("start", b)] for b in range(m))
        cp.Add(leave <= c)
        cp.Add(sum(steps[(a, "home")] for a in range(m)) == leave)
        flows.append((members, steps))
    for j, t in enumerate(tasks):
        count = sum(z for _, z in team[j])
        if t.get("requires") is not None:
            cp.Add(count >= max(1, t.get("min_team") or 1))
            for s in range(skills):
                need = t["requires"][s]
                if need > 0:
                    cp.Add(sum(held[s] * z for held, z in team[j]) >= need)
        else:
            cp.Add(count == t["min_team"])
    cp.Minimize(makespan)
    return cp, flows, m


def follow(solver, flows, n):
    """One route per robot: each kind's flow split into paths from its start."""
    routes = [[] for _ in range(n)]
    for members, steps in flows:
        left = {k: solver.Value(f) for k, f in steps.items() if solver.Value(f) > 0}
        for i in members:
            here = "start"
            while True:
                nxt = next(((a, b) for (a, b) in left if a == here), None)
                if nxt is None:
                    break
                left[nxt] -= 1
                if left[nxt] == 0:
                    del left[nxt]
                here = nxt[1]
                if here == "home":
                    break
                routes[i].append(here)
    return routes


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
    cp, flows, m = model(inst, a.max_wait if a.max_wait is not None else inst["max_wait"])
    solver = cp_model.CpSolver()
    solver.parameters.max_time_in_seconds = a.time_limit
    solver.parameters.num_workers = a.workers
    status = solver.Solve(cp)
    found = status in (cp_model.OPTIMAL, cp_model.FEASIBLE)
    result = {
        "status": solver.StatusName(status),
        "seconds": time.time() - clock,
        "bound": solver.BestObjectiveBound() / SCALE if found else None,
        "routes": follow(solver, flows, len(inst["robots"])) if found else None,
    }
    with open(a.out, "w") as f:
        json.dump(result, f)


if __name__ == "__main__":
    main()

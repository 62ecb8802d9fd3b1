"""The team games of afg instances with OR-Tools CP-SAT and HiGHS, for
`cargo xtask bench-teams` to set beside afg's own exact solver on the same files.

The textbook model (one for both solvers): x_ij = 1 when robot i joins task j (each
robot joins one task, or at most one where the instance allows the void), y_j = 1
when task j is staffed, and b_jn = 1 when task j's n-th member is counted (n = 1 ..
min(capacity, N)), worth F_j(n) - F_j(n - 1):

    maximise   sum_jn (F_j(n) - F_j(n-1)) b_jn  -  beta sum_ij d_ij x_ij
    subject to sum_n b_jn <= sum_i x_ij          (counted members are members)
               b_jn <= y_j                       (only a staffed task earns)
               sum_i x_ij >= k_j y_j             (its threshold)
               sum_i q_is x_ij >= R_js y_j       (its skills)
               sum_i x_ij <= capacity_j

F_j's marginal values decrease, so the counted members are the first ones and a
staffed coalition of n earns exactly F_j(n). CP-SAT needs integer coefficients: the
objective is scaled by 1e6 and rounded (its bound is divided back); HiGHS takes it as
it is. The assignment comes back to afg, which computes its welfare exactly; the bound
is null where the solver has none (CP-SAT before its first solution, HiGHS before its
first bound).

Usage: python scripts/teams_milp.py INSTANCES.jsonl OUT.json --solver cpsat|highs
           --time-limit SECONDS [--threads K] [--log] [--assignments AFG.jsonl]
Needs: pip install ortools highspy numpy
"""

import argparse
import json
import math
import time

import numpy as np

SCALE = 1e6
# The relative gap at which a solve counts as proven: afg's own (`closes` in its
# branch and bound).
PROOF_GAP = 1e-9


def marginal_values(task, count):
    """F_j(k) - F_j(k-1) for k = 1..count, as afg's ValueFunction::marginal."""
    k = np.arange(1, count + 1, dtype=np.float64)
    eps, reward = task["eps"], task["reward"]
    with np.errstate(divide="ignore"):
        v = reward * np.log1p(1.0 / (k + eps - 2.0)) / math.log(eps)
    v[:1] = reward
    return v


def game(instance):
    """Costs (N x M), each task's slot values, thresholds, capacities, skills (N x S)
    and requirements (M x S)."""
    robots = instance["robots"]
    tasks = instance["tasks"]
    n, m = len(robots), len(tasks)
    xy = np.array([[r["x"], r["y"]] for r in robots], dtype=np.float64)
    at = np.array([[t["position"]["x"], t["position"]["y"]] for t in tasks])
    diff = xy[:, None, :] - at[None, :, :]
    cost = instance["beta"] * np.sqrt((diff**2).sum(axis=2))
    capacity = [min(t.get("capacity") or n, n) for t in tasks]
    slots = [marginal_values(t, c) for t, c in zip(tasks, capacity)]
    min_team = [t.get("min_team", 1) for t in tasks]
    s = max([len(r.get("skills", [])) for r in robots] + [len(t.get("requires", [])) for t in tasks])
    skills = np.array([r.get("skills") or [0] * s for r in robots], dtype=np.int64).reshape(n, s)
    requires = np.array([t.get("requires") or [0] * s for t in tasks], dtype=np.int64).reshape(m, s)
    return cost, slots, min_team, capacity, skills, requires


def cpsat(instance, time_limit, threads, log=False):
    from ortools.sat.python import cp_model

    cost, slots, min_team, capacity, skills, requires = game(instance)
    n, m = cost.shape
    model = cp_model.CpModel()
    x = [[model.new_bool_var(f"x{i}_{j}") for j in range(m)] for i in range(n)]
    y = [model.new_bool_var(f"y{j}") for j in range(m)]
    objective = []
    for i in range(n):
        if instance.get("allow_void"):
            model.add(sum(x[i]) <= 1)
        else:
            model.add_exactly_one(x[i])
        objective += [-round(SCALE * cost[i, j]) * x[i][j] for j in range(m)]
    for j in range(m):
        members = sum(x[i][j] for i in range(n))
        counted = [model.new_bool_var(f"b{j}_{k}") for k in range(len(slots[j]))]
        model.add(sum(counted) <= members)
        for b in counted:
            model.add_implication(b, y[j])
        model.add(members >= min_team[j] * y[j])
        model.add(members <= capacity[j])
        for s in range(skills.shape[1]):
            if requires[j, s] > 0:
                model.add(sum(int(skills[i, s]) * x[i][j] for i in range(n)) >= int(requires[j, s]) * y[j])
        objective += [round(SCALE * v) * b for v, b in zip(slots[j], counted)]
    model.maximize(sum(objective))
    solver = cp_model.CpSolver()
    solver.parameters.max_time_in_seconds = time_limit
    solver.parameters.num_workers = threads
    solver.parameters.log_search_progress = log
    start = time.perf_counter()
    status = solver.solve(model)
    seconds = time.perf_counter() - start
    found = status in (cp_model.OPTIMAL, cp_model.FEASIBLE)
    tasks = None
    if found:
        tasks = [next((j for j in range(m) if solver.value(x[i][j])), -1) for i in range(n)]
    return {
        "status": solver.status_name(status).lower(),
        "seconds": seconds,
        "bound": solver.best_objective_bound / SCALE if found else None,
        "tasks": tasks,
    }


def highs(instance, time_limit, threads, log=False):
    import highspy

    cost, slots, min_team, capacity, skills, requires = game(instance)
    n, m = cost.shape
    # Columns: x (i-major), y, then each task's counted members.
    nx = n * m
    first_b = [nx + m]
    for j in range(m):
        first_b.append(first_b[-1] + len(slots[j]))
    ncol = first_b[-1]
    col_cost = np.concatenate([-cost.ravel(), np.zeros(m)] + list(slots))
    lower, upper = np.zeros(ncol), np.ones(ncol)
    for j in range(m):
        if min_team[j] > capacity[j]:
            upper[nx + j] = 0.0
    rows = []  # (lower, upper, indices, values)
    inf = highspy.kHighsInf
    for i in range(n):
        lo = 0.0 if instance.get("allow_void") else 1.0
        rows.append((lo, 1.0, np.arange(i * m, (i + 1) * m), np.ones(m)))
    for j in range(m):
        members = np.arange(j, nx, m)
        counted = np.arange(first_b[j], first_b[j + 1])
        rows.append((-inf, 0.0, np.concatenate([counted, members]),
                     np.concatenate([np.ones(len(counted)), -np.ones(n)])))
        for b in counted:
            rows.append((-inf, 0.0, np.array([b, nx + j]), np.array([1.0, -1.0])))
        rows.append((0.0, inf, np.concatenate([members, [nx + j]]),
                     np.concatenate([np.ones(n), [-float(min_team[j])]])))
        rows.append((-inf, float(capacity[j]), members, np.ones(n)))
        for s in range(skills.shape[1]):
            if requires[j, s] > 0:
                rows.append((0.0, inf, np.concatenate([members, [nx + j]]),
                             np.concatenate([skills[:, s].astype(float), [-float(requires[j, s])]])))
    h = highspy.Highs()
    h.setOptionValue("output_flag", log)
    h.setOptionValue("time_limit", float(time_limit))
    h.setOptionValue("threads", int(threads))
    # HiGHS stops by default at a relative gap of 1e-4, which is not a proof; afg's
    # exact solver closes at 1e-9, and so does HiGHS here.
    h.setOptionValue("mip_rel_gap", PROOF_GAP)
    h.addVars(ncol, lower, upper)
    h.changeColsCost(ncol, np.arange(ncol, dtype=np.int32), col_cost)
    starts = np.cumsum([0] + [len(r[2]) for r in rows[:-1]]).astype(np.int32)
    index = np.concatenate([r[2] for r in rows]).astype(np.int32)
    value = np.concatenate([r[3] for r in rows]).astype(np.float64)
    h.addRows(len(rows), np.array([r[0] for r in rows]), np.array([r[1] for r in rows]),
              len(index), starts, index, value)
    integer = np.arange(nx + m, dtype=np.int32)
    h.changeColsIntegrality(len(integer), integer,
                            np.array([highspy.HighsVarType.kInteger] * len(integer)))
    h.changeObjectiveSense(highspy.ObjSense.kMaximize)
    start = time.perf_counter()
    h.run()
    seconds = time.perf_counter() - start
    info = h.getInfo()
    status = h.modelStatusToString(h.getModelStatus()).lower()
    tasks = None
    if info.primal_solution_status == 2:  # feasible
        col = np.array(h.getSolution().col_value[:nx]).reshape(n, m)
        tasks = [int(np.argmax(row)) if row.max() > 0.5 else -1 for row in col]
    bound = info.mip_dual_bound if math.isfinite(info.mip_dual_bound) else None
    return {"status": status, "seconds": seconds, "bound": bound, "tasks": tasks}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("instances")
    parser.add_argument("out")
    parser.add_argument("--solver", choices=["cpsat", "highs"], required=True)
    parser.add_argument("--time-limit", type=float, required=True)
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--log", action="store_true",
                        help="print the solver's own log (its bound and cuts, round by round)")
    parser.add_argument("--assignments", metavar="FILE",
                        help="also write each answer as an afg-assignment line (what "
                             "`afg solve --method opt --start FILE` starts from)")
    args = parser.parse_args()
    solve = cpsat if args.solver == "cpsat" else highs
    with open(args.instances) as f:
        instances = [json.loads(line) for line in f if line.strip()]
    results = [solve(inst, args.time_limit, args.threads, args.log) for inst in instances]
    with open(args.out, "w") as f:
        json.dump(results, f, allow_nan=False)
    if args.assignments:
        if any(r["tasks"] is None for r in results):
            raise SystemExit(f"{args.solver} found no assignment of some instance within "
                             f"{args.time_limit} s: nothing written to {args.assignments}")
        with open(args.assignments, "w") as f:
            for r in results:
                tasks = [None if t < 0 else t for t in r["tasks"]]
                f.write(json.dumps({"format": "afg-assignment", "version": 1, "tasks": tasks}) + "\n")


if __name__ == "__main__":
    main()

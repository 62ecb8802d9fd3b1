"""Steps per second of the Gymnasium environments against a plain-numpy implementation
of the same MDP (what a user would otherwise write), and the binding's overhead on
``afg.solve(method="opt")`` against the same work timed inside Rust, in one run.

    python crates/afg-py/bench/bench_env.py [--seconds 2] [--json]

Each figure is environment steps per second of wall time with random masked actions
drawn in numpy (the same cost for every row), features in the bounded units.
"""

from __future__ import annotations

import argparse
import json
import time

import gymnasium as gym
import numpy as np

import afg
import afg.gym  # noqa: F401

VALUE_CAP = 4.0  # the bounded units' cap on a task feature's value part, times r_j / eps_j


class NumpyAllocationEnv:
    """The paper's sequential MDP in plain numpy: robots act in index order, the reward
    is the change in welfare, observations are one-hot tasks and the robots' utilities
    u_i(j, n_j^{-i} + 1) in units of beta, the value part capped as in afg's units."""

    def __init__(self, instance: afg.Instance) -> None:
        self.robots, self.tasks = instance.robots, instance.tasks
        self.r, self.eps, self.beta = instance.rewards, instance.eps, instance.beta
        self.n, self.m = len(self.robots), len(self.tasks)
        self.dist = np.linalg.norm(self.robots[:, None, :] - self.tasks[None, :, :], axis=2)

    def value(self, k: np.ndarray) -> np.ndarray:
        """F_j(k) for each task, k >= 0."""
        k = np.asarray(k, dtype=float)
        return np.where(k > 0, self.r * np.log(k + self.eps - 1) / np.log(self.eps), 0.0)

    def observe(self):
        counts = np.bincount(self.assigned[self.assigned >= 0], minlength=self.m)
        member = self.onehot.astype(bool)
        others = counts[None, :] - member
        share = np.minimum(self.value(others + 1) / (others + 1), VALUE_CAP * self.r / self.eps)
        mu = ((share - self.beta * self.dist) / self.beta).astype(np.float32)
        actor = self.t if self.t < self.n else self.n
        return {"robot_features": self.onehot, "task_features": mu, "actor": actor,
                "action_mask": np.ones(self.m, dtype=np.int8)}

    def reset(self):
        self.assigned = np.full(self.n, -1)
        self.onehot = np.zeros((self.n, self.m), dtype=np.float32)
        self.t = 0
        return self.observe(), {}

    def step(self, action: int):
        counts = np.bincount(self.assigned[self.assigned >= 0], minlength=self.m)
        after = counts.copy()
        after[action] += 1
        gain = (self.value(after) - self.value(counts))[action] - self.beta * self.dist[self.t, action]
        self.assigned[self.t] = action
        self.onehot[self.t, action] = 1.0
        self.t += 1
        return self.observe(), float(gain), self.t == self.n, False, {}


def rate(run_steps, seconds: float) -> float:
    steps, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        steps += run_steps()
    return steps / (time.perf_counter() - start)


def single(env, m: int, rng):
    def episode():
        env.reset()
        done, steps = False, 0
        while not done:
            _, _, done, _, _ = env.step(int(rng.integers(m)))
            steps += 1
        return steps
    return episode


def vector(venv, k: int, n: int, m: int, rng):
    venv.reset(seed=0)

    def episode():
        for _ in range(n + 1):  # n steps and the autoreset step
            venv.step(rng.integers(m, size=k))
        return k * n
    return episode


def solve_overhead(n: int, repeats: int) -> dict:
    """Median wall time of ``afg.solve(inst, method="opt")`` from Python against the
    crates' own time for the same call (``stats["core_s"]``: the method, then the
    optimum it is scored against)."""
    inst = afg.generate(robots=n, tasks=5, seed=1)
    python, core = [], []
    for _ in range(repeats):
        start = time.perf_counter()
        res = afg.solve(inst, method="opt")
        python.append(time.perf_counter() - start)
        core.append(res.stats["core_s"])
    p, c = float(np.median(python)), float(np.median(core))
    return {"robots": n, "python_s": p, "rust_s": c, "overhead": (p - c) / c}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=2.0)
    parser.add_argument("--envs", type=int, default=16)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    rows = []
    for n in (60, 1000):
        m = 5
        inst = afg.generate(robots=n, tasks=m, seed=1)
        numpy_env = NumpyAllocationEnv(inst)
        env = gym.make("afg/Allocation-v0", robots=n, tasks=m).unwrapped
        env.reset(seed=0, options={"instance": inst})
        make = lambda copy: gym.make_vec(  # noqa: E731
            "afg/Allocation-v0", num_envs=args.envs, vectorization_mode="vector_entry_point",
            robots=n, tasks=m, copy=copy,
        )
        row = {
            "robots": n,
            "numpy": rate(single(numpy_env, m, rng), args.seconds),
            "afg": rate(single(env, m, rng), args.seconds),
            "afg_vector": rate(vector(make(True), args.envs, n, m, rng), args.seconds),
            "afg_vector_shared": rate(vector(make(False), args.envs, n, m, rng), args.seconds),
        }
        rows.append(row)
    solves = [solve_overhead(n, 50) for n in (1000, 10000)]
    if args.json:
        print(json.dumps({"environments": rows, "solve": solves}, indent=2))
        return
    print(f"| N | numpy env (steps/s) | afg env | afg vector env (K = {args.envs}) | the same, copy=False | vector / numpy | vector / afg env |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        print(
            f"| {r['robots']} | {r['numpy']:,.0f} | {r['afg']:,.0f} | {r['afg_vector']:,.0f} | {r['afg_vector_shared']:,.0f} "
            f"| {r['afg_vector'] / r['numpy']:.1f}x | {r['afg_vector'] / r['afg']:.2f}x |"
        )
    print()
    print("| N (M = 5) | afg.solve(method=\"opt\") from Python | the same inside Rust | overhead |")
    print("|---|---|---|---|")
    for r in solves:
        print(f"| {r['robots']} | {1e3 * r['python_s']:.3f} ms | {1e3 * r['rust_s']:.3f} ms | {100 * r['overhead']:.1f} % |")


if __name__ == "__main__":
    main()

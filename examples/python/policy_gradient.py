"""A small policy-gradient agent (REINFORCE) in plain numpy on the vector environment.

The policy is a softmax over the allowed tasks with logits `theta . phi(j)`, where
phi(j) holds the acting robot's task feature for task j (its utility there) and the
share of robots already in j. It starts as the random policy (theta = 0) and learns
above it within a minute at N = 20.

    python examples/python/policy_gradient.py [--iterations 60]
"""

import argparse
import time

import gymnasium as gym
import numpy as np

import afg.gym  # noqa: F401  (registers afg/Allocation-v0)

parser = argparse.ArgumentParser()
parser.add_argument("--iterations", type=int, default=60)
parser.add_argument("--envs", type=int, default=16)
args = parser.parse_args()

N, M = 20, 5
envs = gym.make_vec("afg/Allocation-v0", num_envs=args.envs, vectorization_mode="vector_entry_point", robots=N, tasks=M)
theta = np.zeros(2)
rng = np.random.default_rng(0)


def features(obs):
    k = np.arange(args.envs)
    actor = np.minimum(obs["actor"], N - 1)
    utility = obs["task_features"][k, actor]  # (K, M)
    share = obs["robot_features"].sum(axis=1) / N  # (K, M)
    return np.stack([utility, share], axis=-1)  # (K, M, 2)


def episode_batch(theta):
    """One episode per sub-environment: the score-function gradient and % of OPT."""
    obs, info = envs.reset(seed=int(rng.integers(2**31)))
    grads, returns = np.zeros((args.envs, 2)), np.zeros(args.envs)
    for _ in range(N):
        phi = features(obs)
        logits = phi @ theta
        logits[~info["action_mask"]] = -np.inf
        p = np.exp(logits - logits.max(axis=1, keepdims=True))
        p /= p.sum(axis=1, keepdims=True)
        actions = np.array([rng.choice(M, p=row) for row in p])
        k = np.arange(args.envs)
        grads += phi[k, actions] - np.einsum("km,kmd->kd", p, phi)
        obs, rewards, terminated, _, info = envs.step(actions)
        returns += rewards
    return grads, returns, info["percent_of_opt"]


start = time.time()
first = None
for it in range(args.iterations):
    grads, returns, percent = episode_batch(theta)
    advantage = (returns - returns.mean()) / (returns.std() + 1e-8)
    theta += 0.5 * (advantage[:, None] * grads).mean(axis=0)
    first = percent.mean() if first is None else first
    if it % 10 == 0 or it == args.iterations - 1:
        print(f"iteration {it:3d}: {percent.mean():6.2f} % of OPT  theta {np.round(theta, 2)}")
print(f"{time.time() - start:.1f} s; from {first:.2f} % (random) to {percent.mean():.2f} % of OPT")
# Seeded throughout, so this is the same run every time: learning must have paid.
if not first < percent.mean() <= 100.0 + 1e-9:
    raise SystemExit(f"the policy did not improve on random ({first:.2f} -> {percent.mean():.2f} %)")

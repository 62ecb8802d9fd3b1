"""A random agent in the Gymnasium environment: it picks a task the mask allows.

    python examples/python/random_agent.py
"""

import gymnasium as gym
import numpy as np

import afg.gym  # noqa: F401  (registers afg/Allocation-v0)

env = gym.make("afg/Allocation-v0", robots=20, tasks=5)
rng = np.random.default_rng(0)
percents = []
for episode in range(20):
    obs, info = env.reset(seed=episode)
    done = False
    while not done:
        action = rng.choice(np.flatnonzero(info["action_mask"]))
        obs, reward, done, truncated, info = env.step(action)
    percents.append(info["percent_of_opt"])
print(f"random agent: {np.mean(percents):.2f} % of OPT over {len(percents)} episodes")
# A valid allocation never beats the optimum, and a random one falls short of it.
if not (0.0 < min(percents) and max(percents) <= 100.0 + 1e-9 and np.mean(percents) < 100.0):
    raise SystemExit(f"a random agent's % of OPT out of range: {percents}")

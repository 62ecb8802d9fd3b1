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

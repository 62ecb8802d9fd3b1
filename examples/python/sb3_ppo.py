"""SuperSuit + stable-baselines3 PPO with parameter sharing on ``mission_v0`` as written
(needs ``pip install stable-baselines3 supersuit torch``; too large for CI, so it runs
as this example).

Every robot is an agent of one shared policy: SuperSuit's
``pettingzoo_env_to_vec_env_v1`` turns the Parallel environment into a vector of
single-agent environments, one per robot, and ``concat_vec_envs_v1`` stacks copies of
it for SB3. ``keep_failed=True`` keeps the set of agents fixed (what those wrappers
need); the observation stays the environment's own ``Dict`` (SB3's
``MultiInputPolicy``), and an action its mask forbids keeps the robot's task, so plain
PPO runs without a masking module. ``--teams`` plays the team game: every task needs
2 or 3 robots at once before its work advances.

The script measures the uniformly random masked policy on held-out missions (seeds
other than training's), trains, and measures the trained policy on the same missions,
its action sampled and its most likely action (a masked choice keeps the robot's task); the return is the team's (the value of all the
work done).

    python examples/python/sb3_ppo.py --teams --steps 500000
"""

from __future__ import annotations

import argparse
import time
from typing import Callable, Dict

import numpy as np

#: Short missions in a wide arena: travel matters, and not every task can be done.
MISSION = dict(robots=10, tasks=12, preset="waves", arena=3.0, horizon=10.0, waves=3, interval=3.0)
#: The team game: each task needs 2 or 3 robots present at once.
TEAMS = dict(min_team=(2, 3))
HELD_OUT = range(1000, 1050)


def make_env(teams: bool):
    from afg.pettingzoo import mission_v0

    return mission_v0.parallel_env(**MISSION, **(TEAMS if teams else {}), keep_failed=True)


def team_return(teams: bool, act: Callable[[Dict[str, np.ndarray]], int], seed: int) -> float:
    """One held-out mission's team return with every robot choosing by ``act``."""
    env = make_env(teams)
    obs, _ = env.reset(seed=seed)
    total = 0.0
    while env.agents:
        obs, rewards, *_ = env.step({a: act(obs[a]) for a in env.agents})
        total += next(iter(rewards.values()), 0.0)
    return total


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--teams", action="store_true", help="tasks need teams of 2-3 robots")
    parser.add_argument("--steps", type=int, default=500_000, help="agent steps of training")
    parser.add_argument("--envs", type=int, default=4, help="missions stepped side by side")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    import supersuit as ss
    from stable_baselines3 import PPO
    from stable_baselines3.common.utils import set_random_seed

    rng = np.random.default_rng(args.seed)
    random_policy = lambda o: int(rng.choice(np.flatnonzero(o["action_mask"])))
    baseline = np.mean([team_return(args.teams, random_policy, s) for s in HELD_OUT])
    print(f"random policy: team return {baseline:.3f} on {len(HELD_OUT)} held-out missions")

    vec = ss.pettingzoo_env_to_vec_env_v1(make_env(args.teams))
    vec = ss.concat_vec_envs_v1(vec, args.envs, num_cpus=0, base_class="stable_baselines3")
    # SuperSuit's SB3 wrapper has no seed() (SB3's PPO(seed=...) calls it): seed the
    # missions through the wrapped vector, and torch and numpy through SB3's helper.
    vec.venv.reset(seed=args.seed)
    set_random_seed(args.seed)
    model = PPO("MultiInputPolicy", vec, n_steps=256, batch_size=640, verbose=0)
    start = time.perf_counter()
    model.learn(total_timesteps=args.steps)
    seconds = time.perf_counter() - start

    print(f"PPO (parameter sharing), {args.steps} agent steps in {seconds:.0f} s:")
    for deterministic, how in [(False, "sampled"), (True, "most likely")]:

        def trained(o: Dict[str, np.ndarray]) -> int:
            action, _ = model.predict(o, deterministic=deterministic)
            return int(action) if o["action_mask"][int(action)] else len(o["action_mask"]) - 1

        score = np.mean([team_return(args.teams, trained, s) for s in HELD_OUT])
        print(f"  {how:>11} action: team return {score:.3f} ({100 * (score / baseline - 1):+.1f} % over random)")


if __name__ == "__main__":
    main()

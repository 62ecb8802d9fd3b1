"""RLlib's PPO with action masking on afg's environments (needs ``pip install
"ray[rllib]" torch``; too large for CI, so it runs as this example).

- ``--env allocation``: ``afg/Allocation-v0``, the paper's sequential MDP, one policy
  acting for each robot in turn; its observation is the acting robot's view (its
  utility in each task) and the tasks' fill shares.
- ``--env mission``: ``afg.pettingzoo.mission_v0``, the mission as a Parallel
  environment, every robot an agent of one shared policy (RLlib's multi-agent API,
  all agents mapped to one module). ``--teams`` plays the team game: every task needs
  2 or 3 robots at once before its work advances.

Both use RLlib's ``ActionMaskingTorchRLModule``, which reads its observation under
``"observations"`` where PettingZoo's key is ``"observation"``: ``mission_env`` renames
the key (and gives the mask as floats) in a ``BaseParallelWrapper``. The script prints the random policy's mean
episode return (measured on the same environment first), then PPO's per iteration.
On a cluster, start Ray there and pass ``--address auto`` (or set ``RAY_ADDRESS``) and
``--env-runners`` to spread sampling over the nodes.

    python examples/python/rllib_ppo.py --env allocation --iterations 20
    python examples/python/rllib_ppo.py --env mission --iterations 20
    python examples/python/rllib_ppo.py --env mission --teams --iterations 20
"""

from __future__ import annotations

import argparse
import time
from typing import Any, Dict, Optional

import gymnasium as gym
import numpy as np

ROBOTS, TASKS = 20, 5
#: Short missions in a wide arena: travel matters, and not every task can be done.
MISSION = dict(robots=10, tasks=12, preset="waves", arena=3.0, horizon=10.0, waves=3, interval=3.0)
#: The team game: each task needs 2 or 3 robots present at once.
TEAMS = dict(min_team=(2, 3))


class AllocationForRLlib(gym.Env):
    """afg/Allocation-v0 with the acting robot's view as a flat observation."""

    def __init__(self, config: Optional[Dict[str, Any]] = None) -> None:
        from afg.gym import AllocationEnv  # imported here: RLlib's workers build it

        self.inner = AllocationEnv(robots=ROBOTS, tasks=TASKS)
        self.observation_space = gym.spaces.Dict(
            {
                "observations": gym.spaces.Box(-np.inf, np.inf, (2 * TASKS,), np.float32),
                "action_mask": gym.spaces.Box(0.0, 1.0, (TASKS,), np.float32),
            }
        )
        self.action_space = gym.spaces.Discrete(TASKS)

    def _view(self, obs: Dict[str, Any]) -> Dict[str, np.ndarray]:
        actor = min(int(obs["actor"]), ROBOTS - 1)
        share = obs["robot_features"].sum(axis=0) / ROBOTS
        flat = np.concatenate([obs["task_features"][actor], share]).astype(np.float32)
        return {"observations": flat, "action_mask": obs["action_mask"].astype(np.float32)}

    def reset(self, *, seed: Optional[int] = None, options: Optional[Dict[str, Any]] = None):
        obs, info = self.inner.reset(seed=seed)
        return self._view(obs), {}

    def step(self, action: int):
        obs, reward, terminated, truncated, info = self.inner.step(int(action))
        return self._view(obs), reward, terminated, truncated, {}


def mission_knobs(teams: bool) -> Dict[str, Any]:
    return dict(MISSION, **(TEAMS if teams else {}))


def mission_env(config: Optional[Dict[str, Any]] = None):
    """mission_v0 for RLlib: its observation key renamed, the mask as floats."""
    from pettingzoo.utils import BaseParallelWrapper
    from ray.rllib.env.wrappers.pettingzoo_env import ParallelPettingZooEnv

    from afg.pettingzoo import mission_v0

    class Renamed(BaseParallelWrapper):
        def __init__(self, env):
            super().__init__(env)
            length = env.observation_space(env.possible_agents[0])["observation"].shape[0]
            self._space = gym.spaces.Dict(
                {
                    "observations": gym.spaces.Box(-np.inf, np.inf, (length,), np.float32),
                    "action_mask": gym.spaces.Box(0.0, 1.0, (MISSION["tasks"] + 1,), np.float32),
                }
            )

        def observation_space(self, agent):
            return self._space

        def _rename(self, obs):
            return {
                a: {"observations": o["observation"], "action_mask": o["action_mask"].astype(np.float32)}
                for a, o in obs.items()
            }

        def reset(self, seed=None, options=None):
            obs, infos = self.env.reset(seed=seed, options=options)
            return self._rename(obs), infos

        def step(self, actions):
            obs, rewards, terminations, truncations, infos = self.env.step(actions)
            return self._rename(obs), rewards, terminations, truncations, infos

    teams = bool((config or {}).get("teams", False))
    return ParallelPettingZooEnv(Renamed(mission_v0.parallel_env(**mission_knobs(teams))))


def random_return(env_name: str, teams: bool, episodes: int) -> float:
    """Mean episode return of the uniformly random masked policy (team return per agent
    for the mission)."""
    rng = np.random.default_rng(0)
    returns = []
    if env_name == "allocation":
        env = AllocationForRLlib()
        for e in range(episodes):
            obs, _ = env.reset(seed=e)
            total, done = 0.0, False
            while not done:
                action = int(rng.choice(np.flatnonzero(obs["action_mask"])))
                obs, reward, done, _, _ = env.step(action)
                total += reward
            returns.append(total)
    else:
        from afg.pettingzoo import mission_v0

        env = mission_v0.parallel_env(**mission_knobs(teams))
        for e in range(episodes):
            obs, _ = env.reset(seed=e)
            total = 0.0
            while env.agents:
                actions = {a: int(rng.choice(np.flatnonzero(obs[a]["action_mask"]))) for a in env.agents}
                obs, rewards, *_ = env.step(actions)
                total += next(iter(rewards.values()), 0.0)
            returns.append(total)
    return float(np.mean(returns))


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--env", choices=["allocation", "mission"], default="allocation")
    parser.add_argument("--teams", action="store_true", help="mission tasks need teams of 2-3 robots")
    parser.add_argument("--iterations", type=int, default=20)
    parser.add_argument("--env-runners", type=int, default=1)
    parser.add_argument("--address", default=None)
    args = parser.parse_args()

    import ray
    from ray.rllib.algorithms.ppo import PPOConfig
    from ray.rllib.core.rl_module.multi_rl_module import MultiRLModuleSpec
    from ray.rllib.core.rl_module.rl_module import RLModuleSpec
    from ray.rllib.examples.rl_modules.classes.action_masking_rlm import ActionMaskingTorchRLModule
    from ray.tune.registry import register_env

    if args.teams and args.env != "mission":
        parser.error("--teams is for --env mission")
    baseline = random_return(args.env, args.teams, 50)
    print(f"random policy: mean episode return {baseline:.3f} (50 episodes)")
    ray.init(address=args.address)
    module = RLModuleSpec(
        module_class=ActionMaskingTorchRLModule,
        model_config={"head_fcnet_hiddens": [64, 64], "head_fcnet_activation": "relu"},
    )
    config = PPOConfig().env_runners(num_env_runners=args.env_runners).training(lr=3e-4)
    if args.env == "allocation":
        register_env("afg-allocation", lambda cfg: AllocationForRLlib(cfg))
        config = config.environment("afg-allocation").rl_module(rl_module_spec=module)
    else:
        register_env("afg-mission", mission_env)
        # RLlib's multi-agent pipeline costs tens of milliseconds an epoch here (the
        # environment itself about one): smaller batches, and time to sample them.
        config = (
            config.environment("afg-mission", env_config={"teams": args.teams})
            .env_runners(sample_timeout_s=1800)
            .training(train_batch_size_per_learner=1000, minibatch_size=250)
            .multi_agent(policies={"shared"}, policy_mapping_fn=lambda agent_id, episode, **kw: "shared")
            .rl_module(rl_module_spec=MultiRLModuleSpec(rl_module_specs={"shared": module}))
        )
    algo = config.build_algo()
    start = time.perf_counter()
    for it in range(1, args.iterations + 1):
        result = algo.train()
        ret = result["env_runners"]["episode_return_mean"]
        if args.env == "mission":
            ret /= MISSION["robots"]  # RLlib sums the agents' (identical) team rewards
        print(f"iteration {it:3}: mean episode return {ret:.3f}  ({time.perf_counter() - start:.0f} s)")
    algo.stop()
    ray.shutdown()


if __name__ == "__main__":
    main()

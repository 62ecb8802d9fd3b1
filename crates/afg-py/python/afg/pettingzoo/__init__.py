"""PettingZoo environments of afg, named as PettingZoo's own are.

- ``allocation_v0``: the paper's sequential allocation MDP as an AEC environment, each
  robot an agent (``from afg.pettingzoo import allocation_v0``;
  ``allocation_v0.env(robots=20, tasks=5)``);
- ``mission_v0``: a mission over time as a Parallel environment, each robot an agent
  deciding from its own view at every decision epoch
  (``mission_v0.parallel_env(robots=20, tasks=8)``; ``mission_v0.env(...)`` is its AEC
  form).

Needs ``pip install pettingzoo``.
"""

from . import allocation_v0, mission_v0

__all__ = ["allocation_v0", "mission_v0"]

"""PettingZoo environments of afg, named as PettingZoo's own are.

- ``allocation_v0``: the paper's sequential allocation MDP as an AEC environment, each
  robot an agent (``from afg.pettingzoo import allocation_v0``;
  ``allocation_v0.env(robots=20, tasks=5)``).

Needs ``pip install pettingzoo``.
"""

from . import allocation_v0

__all__ = ["allocation_v0"]

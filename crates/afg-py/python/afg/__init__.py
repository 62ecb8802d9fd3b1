"""afg: multi-robot task assignment as an alliance formation game.

A thin Python layer over the Rust crates of https://example.invalid/afg: instances and
their generator, every allocator (the exact optimum, GRAPE DA, balanced DA, greedy,
nearest, random, trained models), warm-start reallocation, the exact action values Q*,
missions over time (``afg.Mission``, ``afg.run_mission``, ``afg.MissionEnv``),
schedules of team and skill tasks scored by the makespan (``afg.ScheduleInstance``,
``afg.schedule``, ``afg.score_schedule``), (in
``afg.gym``) the paper's sequential MDP as a Gymnasium environment, and (in
``afg.pettingzoo``) both as PettingZoo environments.

>>> import afg
>>> inst = afg.generate(robots=60, tasks=5, seed=1)
>>> res = afg.solve(inst, method="opt")
>>> res.percent_of_opt
100.0
"""

from __future__ import annotations

from ._errors import AfgError, InvalidInputError, MissingFileError, RefusedError
from ._afg import (
    EnvCore,
    Instance,
    Mission,
    MissionEnv,
    MissionResult,
    Model,
    Result,
    ScheduleInstance,
    VecEnvCore,
    families,
    generate,
    load_model,
    methods,
    q_star,
    read_jsonl,
    reallocate,
    mission_defaults,
    run_mission,
    schedule,
    score,
    score_schedule,
    solve,
    write_jsonl,
)

__all__ = [
    "AfgError",
    "InvalidInputError",
    "MissingFileError",
    "RefusedError",
    "EnvCore",
    "Instance",
    "Mission",
    "MissionEnv",
    "MissionResult",
    "Model",
    "Result",
    "ScheduleInstance",
    "VecEnvCore",
    "families",
    "generate",
    "load_model",
    "methods",
    "q_star",
    "read_jsonl",
    "reallocate",
    "mission_defaults",
    "run_mission",
    "schedule",
    "score",
    "score_schedule",
    "solve",
    "write_jsonl",
]


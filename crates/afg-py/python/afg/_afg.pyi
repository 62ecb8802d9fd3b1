"""Type stubs of the compiled core (afg._afg); the package re-exports every name.

Every error raised here is an ``afg.AfgError`` (``afg/_errors.py``): bad input as
``afg.InvalidInputError`` (also a ``ValueError``), a missing file as
``afg.MissingFileError`` (also a ``FileNotFoundError``), a request refused in the
object's state as ``afg.RefusedError`` (also a ``RuntimeError``)."""

from os import PathLike
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

_Path = Union[str, PathLike]
_Tasks = Union[npt.NDArray[np.int64], Sequence[int]]

class Instance:
    """One game: N robots, M tasks, the distance penalty beta (validated)."""

    def __init__(
        self,
        robots: npt.NDArray[np.float64],
        tasks: npt.NDArray[np.float64],
        rewards: Sequence[float],
        eps: Sequence[float],
        capacities: Optional[_Tasks] = None,
        beta: float = 1.0,
        allow_void: bool = False,
        min_team: Optional[Sequence[int]] = None,
        skills: Optional[Sequence[Sequence[int]]] = None,
        requires: Optional[Sequence[Sequence[int]]] = None,
    ) -> None: ...
    @staticmethod
    def from_json(path: _Path) -> Instance: ...
    @staticmethod
    def parse(text: str) -> Instance: ...
    @staticmethod
    def from_dict(document: Dict[str, Any]) -> Instance: ...
    def to_dict(self) -> Dict[str, Any]: ...
    def to_json(self) -> str: ...
    def write(self, path: _Path) -> None: ...
    @property
    def num_robots(self) -> int: ...
    @property
    def num_tasks(self) -> int: ...
    @property
    def robots(self) -> npt.NDArray[np.float64]: ...
    @property
    def tasks(self) -> npt.NDArray[np.float64]: ...
    @property
    def rewards(self) -> npt.NDArray[np.float64]: ...
    @property
    def eps(self) -> npt.NDArray[np.float64]: ...
    @property
    def capacities(self) -> npt.NDArray[np.int64]: ...
    @property
    def min_team(self) -> npt.NDArray[np.int64]: ...
    @property
    def skills(self) -> npt.NDArray[np.int64]: ...
    @property
    def requires(self) -> npt.NDArray[np.int64]: ...
    @property
    def beta(self) -> float: ...
    @property
    def allow_void(self) -> bool: ...
    def welfare(self, tasks: _Tasks) -> float: ...
    def is_stable(self, tasks: _Tasks, preference: str = "balanced") -> bool: ...
    def ns_rate(self, tasks: _Tasks, preference: str = "balanced") -> float: ...

class Result:
    """An allocation of one instance, scored against the exact optimum."""

    @property
    def tasks(self) -> npt.NDArray[np.int64]: ...
    @property
    def welfare(self) -> float: ...
    @property
    def opt_welfare(self) -> float: ...
    @property
    def percent_of_opt(self) -> Optional[float]: ...
    @property
    def ns_rate_balanced(self) -> float: ...
    @property
    def ns_rate_selfish(self) -> float: ...
    @property
    def coalition_sizes(self) -> npt.NDArray[np.int64]: ...
    @property
    def unassigned(self) -> int: ...
    @property
    def stable_balanced(self) -> bool: ...
    @property
    def stable_selfish(self) -> bool: ...
    def moves(self, preference: str = "balanced") -> npt.NDArray[np.int64]: ...
    @property
    def stats(self) -> Dict[str, float]: ...

class Model:
    """A trained model of a run directory, as an allocator."""

    def allocate(
        self, instance: Instance, reference: bool = True, reference_time_limit: float = 10.0
    ) -> Result: ...

def generate(
    robots: int,
    tasks: int = 5,
    seed: int = 0,
    capacity_slack: Optional[float] = None,
    eps: Optional[float] = None,
    beta: Optional[float] = None,
    rewards: Optional[Tuple[float, float]] = None,
    allow_void: bool = False,
    min_team: Optional[Tuple[int, int]] = None,
    skills: Optional[int] = None,
    skill_share: Optional[float] = None,
    requires: Optional[Tuple[int, int]] = None,
    family: Optional[str] = None,
) -> Instance: ...
def families() -> List[str]: ...
def read_jsonl(path: _Path) -> List[Instance]: ...
def write_jsonl(path: _Path, instances: Sequence[Instance]) -> None: ...
def solve(
    instance: Instance,
    method: Optional[str] = None,
    model: Optional[Union[_Path, Model]] = None,
    seed: int = 0,
    time_limit: Optional[float] = None,
    gap: Optional[float] = None,
    reference: bool = True,
    reference_time_limit: float = 10.0,
    start: Optional[_Tasks] = None,
) -> Result: ...
def score(instance: Instance, tasks: _Tasks) -> Result: ...
def load_model(
    path: _Path, block: Optional[int] = None, repair: bool = False, one_shot: bool = False
) -> Model: ...
def methods() -> List[str]: ...
def reallocate(
    instance: Instance,
    previous_tasks: _Tasks,
    left_robots: Sequence[int] = (),
    left_tasks: Sequence[int] = (),
    method: str = "da-balanced",
) -> Result: ...
def q_star(
    instance: Instance, tasks_so_far: _Tasks, acted: Optional[int] = None
) -> npt.NDArray[np.float64]: ...

class EnvCore:
    """One episode of the sequential MDP (driven by afg.gym.AllocationEnv)."""

    def __init__(
        self,
        instance: Instance,
        units: str = "bounded",
        shaping: str = "none",
        void_action: bool = False,
    ) -> None: ...
    def reset(self, instance: Instance) -> None: ...
    def step(self, action: int) -> Tuple[float, bool]: ...
    def observation(
        self,
    ) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.float32], int, npt.NDArray[np.int8]]: ...
    def q_star(self) -> npt.NDArray[np.float64]: ...
    def tasks(self) -> npt.NDArray[np.int64]: ...
    def welfare(self) -> float: ...
    @property
    def instance(self) -> Instance: ...

class VecEnvCore:
    """K episodes stepped in one call (driven by afg.gym.AllocationVectorEnv)."""

    def __init__(
        self,
        num_envs: int,
        robots: int,
        tasks: int = 5,
        capacity_slack: Optional[float] = None,
        eps: Optional[float] = None,
        beta: float = 1.0,
        units: str = "bounded",
        shaping: str = "none",
        allow_void: bool = False,
        min_team: Optional[Tuple[int, int]] = None,
        skills: Optional[int] = None,
        skill_share: Optional[float] = None,
        requires: Optional[Tuple[int, int]] = None,
    ) -> None: ...
    def reset(self, indices: Sequence[int], seeds: Sequence[int]) -> None: ...
    def step(
        self, actions: Sequence[int], skip: Sequence[bool]
    ) -> Tuple[
        Tuple[npt.NDArray[np.float64], npt.NDArray[np.bool_]],
        Tuple[
            npt.NDArray[np.float32], npt.NDArray[np.float32], npt.NDArray[np.int64], npt.NDArray[np.int8]
        ],
    ]: ...
    def observations(
        self,
    ) -> Tuple[
        npt.NDArray[np.float32], npt.NDArray[np.float32], npt.NDArray[np.int64], npt.NDArray[np.int8]
    ]: ...
    def tasks(self, index: int) -> npt.NDArray[np.int64]: ...
    def welfare(self, index: int) -> float: ...
    def instance(self, index: int) -> Instance: ...

class Mission:
    """A mission: robots, tasks that appear with a workload, failures, beta, a horizon."""

    @staticmethod
    def from_json(path: _Path) -> "Mission": ...
    @staticmethod
    def parse(text: str) -> "Mission": ...
    @staticmethod
    def generate(
        preset: str,
        robots: int,
        tasks: int,
        seed: int = 0,
        workload: Optional[Tuple[float, float]] = None,
        speed: Optional[float] = None,
        arena: Optional[float] = None,
        horizon: Optional[float] = None,
        waves: Optional[int] = None,
        interval: Optional[float] = None,
        rate: Optional[float] = None,
        fail_share: Optional[float] = None,
        capacity_slack: Optional[float] = None,
        allow_void: bool = False,
        min_team: Optional[Tuple[int, int]] = None,
        skills: Optional[int] = None,
        skill_share: Optional[float] = None,
        requires: Optional[Tuple[int, int]] = None,
    ) -> "Mission":
        """Draws a mission with every knob of ``afg mission gen``; a knob left at None
        takes its default (``mission_defaults()["generate"]``).

        Raises:
            InvalidInputError: an unknown preset or a knob out of range.
        """
    def to_json(self) -> str: ...
    def write(self, path: _Path) -> None: ...
    @property
    def num_robots(self) -> int: ...
    @property
    def num_tasks(self) -> int: ...
    @property
    def horizon(self) -> float: ...
    @property
    def robot_positions(self) -> npt.NDArray[np.float64]: ...
    @property
    def task_positions(self) -> npt.NDArray[np.float64]: ...
    @property
    def appears(self) -> npt.NDArray[np.float64]: ...
    @property
    def workloads(self) -> npt.NDArray[np.float64]: ...
    @property
    def min_team(self) -> npt.NDArray[np.int64]: ...
    @property
    def skills(self) -> npt.NDArray[np.int64]: ...
    @property
    def requires(self) -> npt.NDArray[np.int64]: ...

class MissionResult:
    """One run of a mission: metrics, timeline, decisions."""

    @property
    def metrics(self) -> Dict[str, Any]: ...
    @property
    def timeline(self) -> Dict[str, npt.NDArray[Any]]: ...
    @property
    def decisions(self) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.int64]]: ...
    def trace_jsonl(self) -> str: ...

class MissionEnv:
    def __init__(
        self,
        mission: Mission,
        sensing: Optional[float] = None,
        comm_radius: float = 0.25,
        decide_every: Optional[float] = None,
        teams: bool = False,
    ) -> None: ...
    @property
    def num_robots(self) -> int: ...
    @property
    def num_tasks(self) -> int: ...
    @property
    def observation_len(self) -> int: ...
    @property
    def time(self) -> float: ...
    def agents(self) -> List[int]: ...
    def observations(self) -> npt.NDArray[np.float32]: ...
    def masks(self) -> npt.NDArray[np.int8]: ...
    def render(self, size: int = 400) -> npt.NDArray[np.uint8]: ...
    def step(self, actions: npt.NDArray[np.int64]) -> Tuple[float, List[int], bool, bool]: ...

def run_mission(
    mission: Mission,
    method: Optional[str] = None,
    model: Optional[_Path] = None,
    warm: bool = False,
    replan: Optional[float] = None,
    latency: Optional[float] = None,
    latency_factor: Optional[float] = None,
    commit: bool = False,
    hysteresis: Optional[float] = None,
    time_limit: Optional[float] = None,
    seed: int = 0,
    trace: bool = False,
    rounds_per_time: Optional[float] = None,
    loss: Optional[float] = None,
    sensing: Optional[float] = None,
    preference: Optional[str] = None,
    epsilon: Optional[float] = None,
    radius: Optional[float] = None,
    knn: Optional[int] = None,
    burst: Optional[float] = None,
    delay: Optional[int] = None,
    activation: Optional[float] = None,
) -> MissionResult:
    """One allocator in the loop of ``mission``, with every knob of ``afg mission run``.

    A swarm knob left at None takes its default (``mission_defaults()``); ``epsilon``
    depends on the mission: 0.001, or 0.01 where its tasks need teams or skills.

    Raises:
        InvalidInputError: a knob out of range, an unknown method, a radio knob with a
            central method, or a central option with ``grape`` or ``auction``.
        MissingFileError: ``model`` names no run directory.
    """

def mission_defaults() -> Dict[str, Dict[str, Any]]:
    """The defaults of the knobs left at None, by keyword: ``{"run": ...}`` for
    ``run_mission``'s swarm knobs, ``{"generate": ...}`` for ``Mission.generate``."""

class ScheduleInstance:
    """A scheduling instance: depots, robots, tasks that need teams (``min_team`` or
    skills), speed and ``max_wait`` (validated); DCMRTA's layout."""

    @staticmethod
    def read(path: _Path) -> List["ScheduleInstance"]: ...
    @staticmethod
    def parse(text: str) -> "ScheduleInstance": ...
    @staticmethod
    def generate(family: str = "dcmrta", robots: int = 20, tasks: int = 50, seed: int = 0) -> "ScheduleInstance": ...
    def to_json(self) -> str: ...
    @property
    def num_robots(self) -> int: ...
    @property
    def num_tasks(self) -> int: ...
    @property
    def max_wait(self) -> float: ...
    @property
    def task_positions(self) -> npt.NDArray[np.float64]: ...
    @property
    def durations(self) -> npt.NDArray[np.float64]: ...
    def lower_bound(self) -> float: ...

def schedule(
    instance: ScheduleInstance,
    time_limit: Optional[float] = None,
    steps: Optional[int] = None,
    seed: int = 0,
    max_wait: Optional[float] = None,
    start: Optional[Sequence[Union[npt.NDArray[np.int64], Sequence[int]]]] = None,
) -> Dict[str, Any]:
    """Plans a schedule: ``routes`` (one int64 array per robot), ``makespan``, ``bound``,
    ``gap``, ``travel``, ``waiting``, ``longest_wait``, ``start``/``finish`` per task,
    ``steps``, ``seconds``. ``start``: routes to improve (the search starts from them
    and keeps them where it finds nothing better)."""

def score_schedule(
    instance: ScheduleInstance,
    routes: Sequence[Union[npt.NDArray[np.int64], Sequence[int]]],
    max_wait: Optional[float] = None,
) -> Dict[str, Any]:
    """Plays anyone's routes under the instance's rules: ``makespan``, ``travel``,
    ``waiting``, ``longest_wait``, ``valid``, ``long_waits`` (robot, task, wait rows),
    ``start``/``finish`` per task, ``time_use`` (``working``, ``driving``, ``waiting``,
    ``idle``: means per robot that add up to the makespan)."""

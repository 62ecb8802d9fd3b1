"""The keyword arguments both PettingZoo environments take as PettingZoo's own do."""

from __future__ import annotations

from typing import Any, Dict, Optional

from .._errors import InvalidInputError


def check_render_mode(render_mode: Optional[str], metadata: Dict[str, Any]) -> None:
    """Refuses a ``render_mode`` that is neither None nor one of ``metadata``'s."""
    if render_mode is not None and render_mode not in metadata["render_modes"]:
        modes = ", ".join(repr(m) for m in [None, *metadata["render_modes"]])
        raise InvalidInputError(f"render_mode {render_mode!r} is not one of {modes}")


def check_max_cycles(max_cycles: Optional[int]) -> Optional[int]:
    """``max_cycles`` as given: None (no limit) or a whole number ≥ 1."""
    if max_cycles is not None and (isinstance(max_cycles, bool) or not isinstance(max_cycles, int) or max_cycles < 1):
        raise InvalidInputError(f"max_cycles must be a whole number ≥ 1 or None, not {max_cycles!r}")
    return max_cycles

"""afg's exceptions: every error the binding raises is an ``afg.AfgError``.

- ``InvalidInputError`` (also a ``ValueError``): an argument, a knob or a file's
  content is out of range or malformed;
- ``MissingFileError`` (also a ``FileNotFoundError``): a file or run directory that
  is not there;
- ``RefusedError`` (also a ``RuntimeError``): a request the object cannot serve in
  its state (an environment whose worker thread has stopped, say).

So ``except ValueError`` and ``except FileNotFoundError`` keep working, and
``except afg.AfgError`` catches all of afg's own.
"""

from __future__ import annotations


class AfgError(Exception):
    """The base of every error afg raises."""


class InvalidInputError(AfgError, ValueError):
    """Bad input: an argument, a knob or a file's content out of range or malformed."""


class MissingFileError(AfgError, FileNotFoundError):
    """A file or run directory that is not there."""


class RefusedError(AfgError, RuntimeError):
    """A request the object cannot serve in its state."""


__all__ = ["AfgError", "InvalidInputError", "MissingFileError", "RefusedError"]

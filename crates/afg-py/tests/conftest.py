"""A skipped test fails the run: every test here is meant to run in CI (set
AFG_ALLOW_SKIPS=1 to run on a machine that lacks an optional package)."""

from __future__ import annotations

import os

import pytest


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    reporter = session.config.pluginmanager.get_plugin("terminalreporter")
    skipped = reporter.stats.get("skipped", []) if reporter is not None else []
    if skipped and os.environ.get("AFG_ALLOW_SKIPS") != "1":
        names = ", ".join(getattr(r, "nodeid", "?") for r in skipped)
        reporter.write_line(f"{len(skipped)} test(s) skipped unexpectedly: {names}", red=True)
        session.exitstatus = pytest.ExitCode.TESTS_FAILED

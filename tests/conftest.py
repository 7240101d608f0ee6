"""Shared test configuration: hypothesis profiles chosen by ``HYPOTHESIS_PROFILE``.

- ``ci`` (default): few examples, no deadline; keeps the suite within minutes on 2 cores.
- ``dev``: a little more search for local runs.
- ``fuzz``: long searches for hunting bugs (``HYPOTHESIS_PROFILE=fuzz pytest``).
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from hypothesis import HealthCheck, settings

settings.register_profile(
    "ci",
    max_examples=25,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
    print_blob=True,
)
settings.register_profile("dev", max_examples=100, deadline=None, print_blob=True)
settings.register_profile(
    "fuzz",
    max_examples=5000,
    deadline=None,
    suppress_health_check=list(HealthCheck),
    print_blob=True,
)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

SHARED = Path(__file__).resolve().parents[1].parent / "shared"
SHARED_DATA = SHARED / "data"


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """The shared real-data folder (``../shared/data``); tests using it skip when absent."""
    if not SHARED_DATA.is_dir():
        pytest.skip(f"shared data not found at {SHARED_DATA} (real-data tests need ../shared)")
    return SHARED_DATA


# -- CI: a missing dependency of the test extra (or the browser) fails, not skips ----------
# ``ALBOT2D_STRICT_SKIPS=1`` (set by .ci/run): a skip whose reason says something the test
# extra or the CI image provides is missing (an import, an extra, numba, Chromium) becomes
# a failure, so a broken install cannot pass CI by skipping what it was meant to test. Skips
# for data CI does not have (../shared) or optional tools outside the extra stay skips.
STRICT_SKIPS = os.environ.get("ALBOT2D_STRICT_SKIPS", "") not in ("", "0")
_MISSING = ("could not import", "not installed", " extra", "chromium", "numba")


def _must_not_skip(report: pytest.CollectReport | pytest.TestReport) -> str | None:
    if not (STRICT_SKIPS and report.skipped) or hasattr(report, "wasxfail"):
        return None  # an expected failure is reported as skipped: not a missing dependency
    longrepr = report.longrepr
    reason = str(longrepr[2] if isinstance(longrepr, tuple) else longrepr)
    return reason if any(word in reason.lower() for word in _MISSING) else None


def _fail(report: pytest.CollectReport | pytest.TestReport, reason: str) -> None:
    report.outcome = "failed"
    report.longrepr = (
        f"ALBOT2D_STRICT_SKIPS: this would have been skipped, but CI must test it: {reason}"
    )


@pytest.hookimpl(hookwrapper=True)
def pytest_make_collect_report(collector: pytest.Collector):  # type: ignore[no-untyped-def]
    outcome = yield
    report = outcome.get_result()
    reason = _must_not_skip(report)
    if reason is not None:
        _fail(report, reason)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo[None]):  # type: ignore[no-untyped-def]
    outcome = yield
    report = outcome.get_result()
    reason = _must_not_skip(report)
    if reason is not None:
        _fail(report, reason)

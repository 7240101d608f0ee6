"""``ALBOT2D_STRICT_SKIPS=1`` (CI): a test skipped for want of a library of the test extra
or of the browser fails instead; a skip for data CI does not have stays a skip. Checked
in a real pytest subprocess with this suite's conftest."""

from __future__ import annotations

from pathlib import Path

import pytest

pytest_plugins = ["pytester"]

_CONFTEST = (Path(__file__).with_name("conftest.py")).read_text(encoding="utf-8")
_TESTS = """
import pytest

def test_library():
    pytest.importorskip("no_such_module_of_the_test_extra")

def test_browser():
    pytest.skip("headless Chromium not installed (Debian: apt-get install -y chromium)")

def test_shared_data():
    pytest.skip("shared data not found at /nowhere (real-data tests need ../shared)")

@pytest.mark.parametrize("backend", ["numba"])
@pytest.mark.xfail(strict=True, reason="a known defect, pinned (on the numba backend)")
def test_known_defect(backend):
    assert False
"""


@pytest.mark.parametrize("strict", ["1", ""])
def test_strict_skips_fail_what_ci_must_test(
    pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch, strict: str
) -> None:
    monkeypatch.setenv("ALBOT2D_STRICT_SKIPS", strict)
    pytester.makeconftest(_CONFTEST.replace("from tests.", "from "))
    pytester.makepyfile(test_probe=_TESTS)
    pytester.makeini("[pytest]\n")
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider", "-rs")
    if strict:
        # An expected failure is reported as skipped; it stays expected, whatever its words.
        result.assert_outcomes(failed=2, skipped=1, xfailed=1)
        result.stdout.fnmatch_lines(["*CI must test it*no_such_module_of_the_test_extra*"])
    else:
        result.assert_outcomes(skipped=3, xfailed=1)

"""A closed pipe: ``albot2d run --out D | head -1`` ends quietly with exit 0, as Unix tools
do (a real shell pipeline and real processes)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys

import pytest

pytestmark = pytest.mark.skipif(shutil.which("head") is None, reason="needs head(1)")


# ``true`` closes the pipe before albot2d writes anything (the failure every time);
# ``head -1`` reads one line first (the failure whenever head exits before the last write).
@pytest.mark.parametrize(("extra", "reader", "lines"), [
    ([], "head -1", 1), (["--json"], "head -1", 1), ([], "true", 0),
])  # fmt: skip
def test_a_reader_that_stops_early_ends_the_run_quietly(tmp_path, extra, reader, lines):
    out = tmp_path / "run"
    command = [sys.executable, "-m", "albot2d", "run", "--max-frames", "60", "--no-figures",
               "--out", str(out), *extra]  # fmt: skip
    # bash's pipefail makes the pipeline's status albot2d's own
    script = "set -o pipefail; " + " ".join(map(shlex_quote, command)) + " | " + reader
    proc = subprocess.run(["bash", "-c", script], capture_output=True, text=True, timeout=300,
                          env=os.environ | {"PYTHONUNBUFFERED": "0"}, check=False)  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert "error" not in proc.stderr.lower() and "Traceback" not in proc.stderr
    assert len(proc.stdout.splitlines()) == lines
    assert (out / "report.json").is_file()  # the run itself finished


def shlex_quote(text: str) -> str:
    import shlex

    return shlex.quote(text)

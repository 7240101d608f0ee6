"""A page opened in a real headless Chromium, for the tests of generated HTML.

``chromium()`` finds the browser (the test skips where there is none); ``probe_page``
opens a copy of a page with a ``<script>`` injected before ``</body>`` that, once the page
has loaded, writes what it found as JSON into ``body``'s ``data-probe`` attribute, and
reads that back from Chromium's ``--dump-dom``.
"""

from __future__ import annotations

import html
import json
import re
import shutil
import subprocess
from pathlib import Path
from typing import Any

import pytest

__all__ = ["chromium", "probe_page"]


def chromium() -> str:
    """The headless browser's path, or skip the test."""
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    pytest.skip("headless Chromium not installed (Debian: apt-get install -y chromium)")


def probe_page(
    page: str, folder: Path, probe: str, *options: str
) -> tuple[dict[str, Any], subprocess.CompletedProcess[str]]:
    """The probe's JSON for ``page`` (its relative links resolved in ``folder``) and the
    browser's run; ``options`` are extra Chromium flags (e.g. ``--window-size=W,H``)."""
    path = folder / "probe.html"
    path.write_text(page.replace("</body>", probe), encoding="utf-8")
    try:
        proc = subprocess.run(
            [chromium(), "--headless", "--no-sandbox", "--disable-gpu", *options,
             "--virtual-time-budget=5000", "--dump-dom", path.as_uri()],
            capture_output=True, text=True, timeout=120, check=False,
        )  # fmt: skip
    finally:
        path.unlink()
    found = re.search(r'data-probe="([^"]*)"', proc.stdout)
    assert found, proc.stderr[-2000:]
    return json.loads(html.unescape(found.group(1))), proc

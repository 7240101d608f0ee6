"""``python -m benchmarks.report`` regenerates docs/benchmarks.md: its quick mode writes a
page with the machine, the load, the kernels and a row per measurement."""

from __future__ import annotations

from pathlib import Path

from benchmarks.report import main


def test_the_report_command_writes_the_page(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "benchmarks.md"
    assert main(["--quick", "--out", str(out)]) == 0
    page = out.read_text(encoding="utf-8")
    assert capsys.readouterr().out == page + "\n"  # printed as written
    assert "- machine: " in page and "load average" in page and "kernels " in page
    rows = [line for line in page.splitlines() if line.startswith("| ") and "---" not in line]
    assert rows[0] == "| what | measured | how |"
    what = [r.split(" | ")[0].removeprefix("| ") for r in rows[1:]]
    assert "line extraction, 361-beam scan" in what
    assert "Albot₁ per view (extraction excluded)" in what
    assert any(w.startswith("`Simulator.step` with a 181-beam scan") for w in what)
    for row in rows[1:]:  # every value a positive number
        value = row.split(" | ")[1]
        number = float(value.split()[0].replace(",", ""))
        assert number > 0, row

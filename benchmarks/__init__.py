"""Benchmarks (pytest-benchmark); not collected by the default test run."""

__all__: list[str] = []

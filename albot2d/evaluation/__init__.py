"""Evaluation: relative pose error, homing, map quality, experiments."""

__all__: list[str] = []

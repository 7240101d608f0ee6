"""Perception: laser points → surfaces (line extraction, occlusion) and surface tracking."""

__all__: list[str] = []

"""Mapping: the Albot1 view-based mapper, its route and global maps, and the Albot_x baselines."""

__all__: list[str] = []

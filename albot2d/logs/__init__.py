"""Robot log I/O: CARMEN logs (read and write) and Kümmerle relations files."""

__all__: list[str] = []

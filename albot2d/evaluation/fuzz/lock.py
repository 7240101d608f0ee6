"""The lock that keeps two campaigns from writing one folder.

``CampaignLock(folder)`` holds ``folder/campaign.lock`` while a campaign runs: an exclusive
``fcntl.flock`` on the file, which holds the owner's pid (for the message a second
campaign prints). The kernel drops a flock when its process dies, however it dies, so the
lock left behind by a killed campaign (``kill -9``, a power cut) is stale at once and the
next campaign takes it. Where ``fcntl`` does not exist (Windows) the file is created with
``O_EXCL`` instead, and a lock whose pid no longer runs is taken as stale and replaced.
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path
from types import TracebackType

from albot2d.errors import InputError

try:
    import fcntl
except ImportError:  # pragma: no cover - not POSIX
    # No fcntl here: None marks the lock as unavailable (checked before every use).
    fcntl = None  # type: ignore[assignment]

__all__ = ["LOCK_NAME", "CampaignLock"]

LOCK_NAME = "campaign.lock"


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # runs, as another user
        return True
    return True


def _read_pid(path: Path) -> int | None:
    try:
        text = path.read_text(encoding="ascii").strip()
    except (OSError, UnicodeDecodeError):
        return None
    return int(text) if text.isdigit() else None


class CampaignLock:
    """An exclusive lock on a campaign folder for this process (a context manager)."""

    def __init__(self, folder: str | os.PathLike[str]) -> None:
        self.path = Path(folder) / LOCK_NAME
        self._fd: int | None = None

    def _busy(self, pid: int | None) -> InputError:
        holder = f"pid {pid}" if pid is not None else "another process"
        return InputError(
            f"{self.path.parent} is in use by another campaign ({holder} holds "
            f"{self.path}); wait for it to end or use another --out"
        )

    def acquire(self) -> CampaignLock:
        if fcntl is None:
            return self._acquire_exclusive()
        while True:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                os.close(fd)
                raise self._busy(_read_pid(self.path)) from None
            # The holder before us unlinks the file as it releases it: a lock on an
            # unlinked file locks nothing, so try again on the file now at the path.
            try:
                same = os.stat(self.path).st_ino == os.fstat(fd).st_ino
            except FileNotFoundError:
                same = False
            if same:
                break
            os.close(fd)
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()}\n".encode("ascii"))
        self._fd = fd
        return self

    def _acquire_exclusive(self) -> CampaignLock:
        for _ in range(2):
            try:
                fd = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_EXCL, 0o644)
            except FileExistsError:
                pid = _read_pid(self.path)
                if pid is not None and _pid_alive(pid):
                    raise self._busy(pid) from None
                with contextlib.suppress(FileNotFoundError):
                    self.path.unlink()  # stale: its campaign died
                continue
            os.write(fd, f"{os.getpid()}\n".encode("ascii"))
            self._fd = fd
            return self
        raise self._busy(_read_pid(self.path))

    def release(self) -> None:
        if self._fd is None:
            return
        with contextlib.suppress(FileNotFoundError):
            self.path.unlink()  # before unlocking, so a waiter retries on a fresh file
        os.close(self._fd)  # closing drops the flock
        self._fd = None

    def __enter__(self) -> CampaignLock:
        return self.acquire()

    def __exit__(
        self,
        kind: type[BaseException] | None,
        value: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.release()

"""The Rerun viewer options of ``run`` and ``replay``: ``--rerun``, ``--rerun-url``,
``--rerun-save`` (``albot2d.viz.rerun_log``; the ``[rerun]`` extra)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from albot2d.errors import InputError

if TYPE_CHECKING:
    from albot2d.viz.rerun_log import RerunLog

__all__ = ["add_viewer_options", "check_viewer_options", "open_viewer"]


def add_viewer_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("viewer (the [rerun] extra)")
    g.add_argument(
        "--rerun",
        action="store_true",
        help="stream the run to a live Rerun viewer: the one running (--rerun-url) or, "
        "if none is, a new one",
    )
    g.add_argument(
        "--rerun-url",
        metavar="URL",
        help="the viewer to stream to, e.g. rerun+http://HOST:9876/proxy (implies --rerun; "
        "never starts one)",
    )
    g.add_argument(
        "--rerun-save",
        metavar="FILE.rrd",
        help="write the Rerun recording to FILE.rrd (open it with: rerun FILE.rrd)",
    )


def check_viewer_options(args: argparse.Namespace) -> bool:
    """Check the viewer options (before anything is written); whether a viewer is asked
    for."""
    import importlib.util

    live = bool(args.rerun or args.rerun_url)
    save = args.rerun_save
    if not live and save is None:
        return False
    if save is not None:
        parent = Path(save).parent
        out = getattr(args, "out", None)  # the output directory is made before the run
        if not parent.is_dir() and not (out and parent.resolve() == Path(out).resolve()):
            raise InputError(f"--rerun-save {save}: its directory does not exist")
        if not str(save).endswith(".rrd"):
            raise InputError(f"--rerun-save {save}: give a .rrd file name")
    if args.rerun_url is not None and not args.rerun_url.startswith(("rerun://", "rerun+http")):
        raise InputError(
            f"--rerun-url {args.rerun_url!r}: a viewer URL looks like "
            "rerun+http://127.0.0.1:9876/proxy"
        )
    if importlib.util.find_spec("rerun") is None:
        from albot2d.viz.rerun_log import MISSING_EXTRA

        raise InputError(MISSING_EXTRA)
    return True


def open_viewer(args: argparse.Namespace, name: str) -> RerunLog | None:
    """A ``RerunLog`` for the (checked) viewer options, or None."""
    if not check_viewer_options(args):
        return None
    from albot2d.viz.rerun_log import RerunLog

    live = bool(args.rerun or args.rerun_url)
    return RerunLog(name, save=args.rerun_save, live=live, url=args.rerun_url)

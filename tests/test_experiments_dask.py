"""``albot2d experiments --backend dask``: a real dask cluster on 127.0.0.1 gives the same
experiments.json as the local backend, bit for bit (the wall time aside)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from albot2d.cli import main

# two seeds of the two cheap start-stop experiments: several jobs in flight at once
_ARGS = ["--quick", "--only", "table1", "fig15", "--seeds", "0-1", "--no-figures"]


def _comparable(out: Path) -> dict:
    data = json.loads((out / "experiments.json").read_text())
    data.pop("wall_time_s")
    return data


def test_dask_backend_equals_the_local_backend_bit_for_bit(tmp_path: Path) -> None:
    distributed = pytest.importorskip("dask.distributed")
    local = tmp_path / "local"
    assert main(["experiments", *_ARGS, "--workers", "1", "--out", str(local)]) == 0
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  protocol="tcp://", host="127.0.0.1",
                                  dashboard_address=None) as cluster:  # fmt: skip
        assert cluster.scheduler_address.startswith("tcp://127.0.0.1:")
        dask = tmp_path / "dask"
        assert main(["experiments", *_ARGS, "--backend", "dask", "--address",
                     cluster.scheduler_address, "--out", str(dask)]) == 0  # fmt: skip
    expected = _comparable(local)
    assert _comparable(dask) == expected
    # the runs really happened: both journeys, both seeds, stops on them
    assert sorted(expected["runs"]) == [
        "fig15_room",
        "fig6_start_stop",
        "fig8_anticlockwise",
        "fig8_clockwise",
    ]
    assert expected["experiments"]["table1"]["ours"]["n_stops"] > 0
    assert set(expected["runs"]["fig15_room"]["per_seed"]) == {"0", "1"}

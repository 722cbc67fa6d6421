"""`upd disk` under `mpirun -n 2` gives the serial fan diagram (the NDs shared over the ranks)."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from test_disk import coarse_geometry_file

pytestmark = pytest.mark.mpi


def _run(tmp: Path, geo: Path, ranks: int) -> dict:
    exe = shutil.which("mpirun")
    if exe is None:
        pytest.fail("mpirun is not installed")
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", UPD_NO_PROGRESS="1")
    argv = [sys.executable, "-m", "workbench.cli.main", "disk", "--geometry", str(geo),
            "--damper", "cylinder", "--n-blades", "6", "--families", "2",
            "--out", str(tmp / f"out{ranks}"), "--json"]  # fmt: skip
    if ranks > 1:
        argv = [exe, "-n", str(ranks), "--allow-run-as-root", "--oversubscribe", *argv]
    p = subprocess.run(argv, capture_output=True, text=True, timeout=300, env=env)
    assert p.returncode == 0, p.stderr[-3000:]
    return json.loads(p.stdout)


def test_upd_disk_under_mpirun_gives_the_serial_fan(tmp_path):
    geo = coarse_geometry_file(tmp_path)
    one, two = _run(tmp_path, geo, 1), _run(tmp_path, geo, 2)
    assert two["ranks"] == 2 and one["ranks"] == 1
    for key in ("fan_hz_stuck", "fan_hz_free"):
        a, b = np.array(one[key]), np.array(two[key])
        assert a.shape == (4, 2)
        assert np.abs(a - b).max() <= 1e-3  # both rounded to 1e-3 Hz: the same numbers
    assert Path(two["files"]["fan_png"]).is_file()

"""build_geometry under mpirun: rank 0 meshes, every rank gets the same record and errors."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys

import pytest

SCRIPT = """
import json, sys
from pathlib import Path
from mpi4py import MPI
from workbench.errors import InputError
from workbench.geometry import build_geometry
ov = {"rig": {"mesh": {"size_mm": 10.0, "contact_size_mm": 2.5, "damper_size_mm": 5.0}}}
g = build_geometry("cone", Path(sys.argv[1]), overrides=ov)
try:
    build_geometry("cone", Path(sys.argv[1]), overrides={"cone": {"semi_angle_deg": 60.0}})
    err = None
except InputError as e:
    err = e.param
print(json.dumps({"rank": MPI.COMM_WORLD.rank, "digest": g.digest, "pairs": g.contact.n_pairs,
                  "gap": g.stats["max_pair_gap_m"], "err": err}), flush=True)
"""


@pytest.mark.mpi
@pytest.mark.skipif(shutil.which("mpirun") is None, reason="mpirun is not installed")
def test_two_ranks_share_one_build(tmp_path):
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    cmd = [
        "mpirun",
        "-n",
        "2",
        "--oversubscribe",
        "-x",
        "OMP_NUM_THREADS=1",
        sys.executable,
        "-c",
        SCRIPT,
        str(tmp_path),
    ]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=300, env=env)
    assert p.returncode == 0, p.stderr[-3000:]
    rows = [json.loads(line) for line in p.stdout.splitlines() if line.startswith("{")]
    assert sorted(r["rank"] for r in rows) == [0, 1]
    assert len({r["digest"] for r in rows}) == 1
    assert all(r["pairs"] == 46 and r["gap"] <= 1e-9 for r in rows)
    # the InputError is raised on every rank, not only where it was found
    assert all(r["err"] == "cone.semi_angle_deg" for r in rows)

"""A study on two MPI ranks hands its cases and backbones to both, and ends: every rank exits.

A rank that works alone on its own communicator can leave PETSc objects whose
clean-up at exit is collective, which the other rank never joins: the job
then prints its answer and never ends (seen with PETSc 3.18 when each rank
drew its own dampers' pictures). ``make run`` is such a job, so this runs in
the default suite.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from tests.conftest import ROOT, TINY

pytestmark = [pytest.mark.mpi, pytest.mark.xdist_group("mpi-schedule")]


def test_two_ranks_share_the_cases_and_the_backbones_and_exit(tmp_path):
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    out = tmp_path / "mpi"
    p = subprocess.run(
        ["mpirun", "-n", "2", "--oversubscribe", "-x", "OMP_NUM_THREADS=1",
         "-x", "OPENBLAS_NUM_THREADS=1", "-x", "UPD_NO_PROGRESS=1",
         sys.executable, "-m", "workbench.cli.main", "study", str(TINY), "--phases", "0,180",
         "--nonlinear-modes", "--out", str(out), "--json"],
        cwd=ROOT, capture_output=True, text=True, timeout=600, env=env,
    )  # fmt: skip
    assert p.returncode == 0, p.stderr[-3000:]
    summary = json.loads(p.stdout.replace("\x1b[0m", ""))
    sched = json.loads((out / "schedule.json").read_text())
    # every case once, handed out costliest first to whichever rank was free: both worked
    names = sorted(r["case"] for r in sched["records"])
    assert names == sorted(c["case"] for c in summary["cases"])
    assert {r["rank"] for r in sched["records"]} == {0, 1}
    assert len(sched["busy_per_rank_s"]) == 2 and 0 < sched["efficiency"] <= 1 + 1e-9
    assert summary["schedule"]["ranks"] == 2
    # the two backbones (one per family) were computed, one on each rank
    assert "[1] I workbench.studies.engine.nlmodes: backbone" in p.stderr
    assert "[0] I workbench.studies.engine.nlmodes: backbone" in p.stderr

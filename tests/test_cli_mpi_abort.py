"""Under mpirun, an error raised on one rank only ends the whole job instead of hanging it."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys

from tests.conftest import ROOT

SCRIPT = """
import sys
from mpi4py import MPI
import workbench.cli.cmd_report as cmd

def run(args, ctx):
    if MPI.COMM_WORLD.rank == 1:
        raise RuntimeError("boom on rank 1 only")
    MPI.COMM_WORLD.Barrier()  # rank 0 waits here for ever unless the job is aborted
    return {}

cmd.run = run
from workbench.cli.main import main
sys.exit(main(["report", "."]))
"""


def test_an_error_on_one_rank_aborts_every_rank(tmp_path):
    exe = shutil.which("mpirun")
    assert exe, "mpirun is not installed (scripts/setup.sh installs OpenMPI)"
    script = tmp_path / "one_rank_fails.py"
    script.write_text(SCRIPT)
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", PYTHONPATH=str(ROOT))
    p = subprocess.run(
        [exe, "-n", "2", "--allow-run-as-root", "--oversubscribe", sys.executable, str(script)],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
        cwd=tmp_path,
    )
    # a hang would end in the timeout above; an abort ends the job with a non-zero code
    assert p.returncode != 0
    err = p.stderr + p.stdout
    assert "internal error: RuntimeError: boom on rank 1 only" in err
    assert "rank 1 failed; aborting all ranks" in err

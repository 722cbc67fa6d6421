"""A study killed at any moment resumes; uninterrupted and under mpirun it answers the same."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import ROOT, TINY, run_upd

pytestmark = pytest.mark.xdist_group("resume")
KEYS = ("peak_frequency_hz", "peak_amplitude_mm", "friction_energy_mj")


def _cases(j):
    return {c["case"]: c for c in j["cases"]}


def _report_shape(out):
    """What a study's report shows, without the times (the manifest's summary and sections)."""
    m = json.loads((out / "manifest.json").read_text())
    return {
        "summary": m["summary"],
        "inputs": m["inputs"],
        "sections": [
            (
                s["id"],
                s["title"],
                s["text"],
                [f["path"] for f in s["figures"]],
                [t["path"] for t in s["tables"]],
            )
            for s in m["sections"]
        ],
    }


def test_killed_study_resumes_and_reuses_its_work(tiny_resumed, tmp_path):
    out, first = tiny_resumed  # SIGKILLed after its first case, then resumed
    assert first["n_reused"] >= 1 and first["n_reused"] + first["n_computed"] == 2
    serial = _cases(first)
    out = Path(shutil.copytree(out, tmp_path / "tiny"))

    resumed_shape = _report_shape(out)
    # the last run of a resumed study may find every case cached (the run before it killed
    # after its curves, before the model pictures): its report still has the pictures and
    # lists the reused work with what it cost when it was computed
    for p in [*(out / "figures").glob("*"), out / "report.html", out / "manifest.json"]:
        p.unlink()
    r2 = run_upd("study", TINY, "--out", out, "--json")
    assert r2.code == 0 and r2.json["n_reused"] == 2 and r2.json["n_computed"] == 0
    again = _cases(r2.json)
    assert all(again[k][q] == serial[k][q] for k in serial for q in KEYS)
    for name in ("model_cone.png", "modes_cone.png"):
        assert (out / "figures" / name).is_file()
    assert _report_shape(out) == resumed_shape  # the same report, rebuilt from the cache
    reused = {
        k.split(",")[0]: v
        for k, v in json.loads((out / "manifest.json").read_text())["timings"].items()
        if "reused from the cache" in k
    }
    assert {"geometry", "reduction rig", "reduction damper", "cases (2)"} <= set(reused)
    # the cases cost what their own runs measured (not this run's 0.01 s)
    assert reused["cases (2)"] == pytest.approx(sum(c["wall_s"] for c in first["cases"]), abs=0.01)
    assert reused["reduction rig"] > 0.5 and reused["geometry"] > 0.1


# slow (about 2 min of the default run: an uninterrupted serial and a 2-rank run of the
# tiny study); run by `make test-slow` with the benchmarks
@pytest.mark.slow
def test_uninterrupted_and_two_rank_runs_match_the_resumed_one(tiny_resumed, tmp_path):
    out, first = tiny_resumed
    serial = _cases(first)
    out = Path(shutil.copytree(out, tmp_path / "tiny"))
    resumed_shape = _report_shape(out)
    rf = run_upd("study", TINY, "--out", out, "--json", "--force")  # uninterrupted
    assert rf.code == 0 and rf.json["n_computed"] == 2
    assert _report_shape(out) == resumed_shape

    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    mp = subprocess.run(
        [
            "mpirun",
            "-n",
            "2",
            "--oversubscribe",
            "-x",
            "OMP_NUM_THREADS=1",
            "-x",
            "OPENBLAS_NUM_THREADS=1",
            "-x",
            "UPD_NO_PROGRESS=1",
            sys.executable,
            "-m",
            "workbench.cli.main",
            "study",
            str(TINY),
            "--out",
            str(tmp_path / "mpi"),
            "--json",
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=1200,
        env=env,
    )
    assert mp.returncode == 0, mp.stderr[-3000:]

    # under mpirun the ranks' stdout is a pseudo-terminal, and something in the run writes
    # a colour reset (ESC [0m) to it that reaches mpirun's stdout (also before issue 13);
    # the JSON itself is whole
    par = _cases(json.loads(mp.stdout.replace("\x1b[0m", "")))
    assert set(par) == set(serial)
    for k in serial:
        for q in KEYS:
            # the reduction differs by round-off between 1 and 2 ranks (1e-11 relative)
            assert par[k][q] == pytest.approx(serial[k][q], rel=1e-6), (k, q)

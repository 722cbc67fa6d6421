"""``upd nlmodes`` on a model file and (slow) on a study file, and the study report."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys

import pytest
from conftest import ROOT, assert_nonblank, run_upd


def test_nlmodes_model_file(tmp_path):
    out = tmp_path / "nm"
    r = run_upd(
        "nlmodes",
        ROOT / "studies" / "examples" / "two_dof_contact.toml",
        "--levels",
        "2",
        "--harmonics",
        "0,1,2,3",
        "--nt",
        "64",
        "--compare",
        "--json",
        "--out",
        out,
    )
    assert r.code == 0, r
    s = r.json
    bb = s["backbone"]
    assert bb["completed"] and bb["f_stuck_hz"] == pytest.approx(186.42, rel=1e-3)
    assert bb["freq_last_hz"] < 100.0 < bb["freq_at_damping_max_hz"]
    assert len(s["levels"]) == 1
    for row in s["levels"]:
        assert row["valid"]
        assert abs(row["error_pct"]) < 2.0  # synthesis against the full HBM of the level
    for key in ("backbone_png", "synthesis_png"):
        assert_nonblank(s["files"][key])
    assert (out / "backbone.h5").is_file() and (out / "backbone.csv").is_file()
    assert json.loads((out / "summary.json").read_text())["name"] == "two_dof_contact"


def test_nlmodes_bad_input(tmp_path):
    r = run_upd(
        "nlmodes",
        ROOT / "studies" / "examples" / "two_dof_contact.toml",
        "--range",
        "1",
        "--out",
        tmp_path,
    )
    assert r.code == 2 and "--range" in r.err
    r = run_upd("nlmodes", tmp_path / "missing.toml")
    assert r.code == 2


@pytest.mark.slow
def test_study_with_nonlinear_modes(tmp_path):
    """The smallest real study with its backbone, synthesis and HBM check in the report."""
    out = tmp_path / "tiny"
    r = run_upd(
        "study",
        ROOT / "tests" / "studies" / "tiny.toml",
        "--nonlinear-modes",
        "--no-stability",
        "--json",
        "--out",
        out,
        timeout=3000,
    )
    assert r.code == 0, r
    man = json.loads((out / "manifest.json").read_text())
    ids = [s["id"] for s in man["sections"]]
    assert "nlmodes" in ids and "nlmodes-synthesis" in ids
    for sec in man["sections"]:
        if sec["id"].startswith("nlmodes"):
            for f in sec["figures"]:
                assert_nonblank(out / f["path"])
    html = (out / "report.html").read_text()
    assert "backbone" in html
    tiny = ROOT / "tests" / "studies" / "tiny.toml"

    def nlmodes_rows() -> list[dict]:
        # with the study's options: --no-stability is part of the cases' keys
        r = run_upd("nlmodes", tiny, "--no-stability", "--json", "--out", out)
        assert r.code == 0, r
        return r.json["rows"]

    # a second run reuses the backbone (cached with the cases)
    rows = nlmodes_rows()
    assert rows and all(row["hbm_peak_amplitude_mm"] is not None for row in rows)
    # under mpirun with every case cached, the backbones (rank 0) still need the models,
    # whose loading is collective: all ranks load them first (it used to hang here)
    shutil.rmtree(out / "cache" / "nlmodes")
    exe = shutil.which("mpirun")
    assert exe, "mpirun is needed"
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", UPD_NO_PROGRESS="1")
    cmd = [exe, "-n", "2", "--allow-run-as-root", "--oversubscribe", sys.executable]
    cmd += ["-m", "workbench.cli.main", "study", str(tiny)]
    cmd += ["--nonlinear-modes", "--no-stability", "--json", "--out", str(out)]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=900, cwd=ROOT, env=env)
    assert p.returncode == 0, p.stderr[-3000:]
    assert (out / "cache" / "nlmodes").is_dir()  # computed again, on rank 0
    for a, b in zip(rows, nlmodes_rows(), strict=True):  # the same backbone and synthesis
        assert b["syn_peak_amplitude_mm"] == pytest.approx(a["syn_peak_amplitude_mm"], rel=1e-6)


def test_cost_rows_report_the_harmonic_1_error_beside_the_max_abs_error():
    """The cost row gives the worst max|x| error and the worst harmonic-1 error of the
    valid rows (the paper rig's cone in phase at 3.84 N: -5.2 % in max|x|, -3.7 % in
    harmonic 1, the two responses' mean terms differing), and the worst of all rows."""
    from workbench.studies.engine.nlmodes import cost_rows

    def row(err, h1_err, valid=True):
        return {"label": "cone, in-phase", "hbm_seconds": 1.0, "syn_seconds": 0.01,
                "valid": valid, "error_pct": err, "h1_error_pct": h1_err}  # fmt: skip

    res = {
        "backbones": [{"label": "cone, in-phase", "seconds": 0.5}],
        "rows": [row(-5.22, -3.71), row(0.02, 0.01), row(-9.0, -7.0, valid=False)],
    }
    (c,) = cost_rows(res)
    assert c["max_error_valid_pct"] == 5.22 and c["max_h1_error_valid_pct"] == 3.71
    assert c["max_error_all_pct"] == 9.0 and c["n_valid"] == 2

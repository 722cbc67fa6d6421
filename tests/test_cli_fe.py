"""``upd modes`` and ``upd reduce`` as a user runs them (separate processes).

A coarse rig (``--size 12`` mm, about 20k DOFs) keeps these fast; the
default meshes are exercised by the slow tests in test_fe_defaults.py.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys

import pytest
from conftest import ROOT, assert_nonblank, run_upd

from workbench.reduced import ReducedModel


def test_modes_cylinder_coarse(tmp_path):
    """Stuck cylinder: first bending pair named; out-of-phase within 350-450 Hz (item 7).

    The coarse rig mesh shifts the default-mesh value (404 Hz) by under 1 %.
    """
    r = run_upd(
        "modes", "--damper", "cylinder", "--size", "12", "--n", "4", "--out", tmp_path, "--json"
    )
    assert r.code == 0, r
    s = r.json
    assert s["contact"] == "stuck" and len(s["freqs_hz"]) == 4
    f_in = s["first_bending_in_phase"]["freq_hz"]
    f_out = s["first_bending_out_of_phase"]["freq_hz"]
    assert 350.0 <= f_out <= 450.0
    assert f_in < f_out  # the cylinder rolls: in phase it barely loads its springs
    assert (
        s["modes"][s["first_bending_out_of_phase"]["mode"] - 1]["label"]
        == "first bending out-of-phase"
    )
    for key in ("modes_rig_xdmf", "modes_damper_xdmf"):
        assert (tmp_path / os.path.basename(s["files"][key])).is_file()
    # ParaView/meshio/pyvista files: mode numbers from 1, each VTU with its frequency
    import meshio
    import pyvista as pv

    reader = pv.get_reader(s["files"]["modes_rig_pvd"])
    assert list(reader.time_values) == [1.0, 2.0, 3.0, 4.0]
    for k, f in enumerate(s["freqs_hz"]):
        m = meshio.read(tmp_path / "modes_rig" / f"mode_{k + 1:02d}.vtu")
        assert round(float(m.field_data["freq_hz"][0]), 3) == f
        assert m.point_data["mode_shape"].shape == (len(m.points), 3)
    mesh = meshio.read(tmp_path / "geometry" / "rig.vtu")
    assert [c.type for c in mesh.cells] == ["tetra10"]
    assert pv.read(tmp_path / "geometry" / "damper.vtu").volume > 0
    assert_nonblank(tmp_path / "first_bending.png")
    assert json.loads((tmp_path / "modes.json").read_text())["freqs_hz"] == s["freqs_hz"]


def test_reduce_wedge_coarse_then_reuse(tmp_path):
    """Reduced models written, the stuck check agrees with a rerun that reuses them."""
    args = (
        "reduce",
        "--damper",
        "wedge",
        "--size",
        "12",
        "--modes",
        "6",
        "--rigid-damper",
        "--out",
        tmp_path,
        "--json",
    )
    r = run_upd(*args)
    assert r.code == 0, r
    s = r.json
    assert s["bodies"]["damper"]["kind"] == "rigid" and s["bodies"]["damper"]["n_reduced"] == 6
    assert s["bodies"]["rig"]["n_interface_nodes"] == 146 + 4  # wedge: 146 pairs + 4 points
    assert not s["bodies"]["rig"]["reused"]
    rig = ReducedModel.load(tmp_path / "rig.h5")
    rig.check()
    assert rig.n == 3 * 150 + 6
    again = run_upd(*args)
    assert again.code == 0, again
    assert again.json["bodies"]["rig"]["reused"] and again.json["bodies"]["damper"]["reused"]
    assert again.json["stuck_reduced"] == s["stuck_reduced"]
    assert 350.0 <= s["stuck_reduced"]["first_bending_out_of_phase_hz"] <= 450.0


@pytest.mark.parametrize(
    "args, word",
    [
        (("modes", "--damper", "cone", "--contact", "slipping"), "contact"),
        (("modes", "--damper", "cone", "--n", "0"), "n = 0"),
        (("modes", "--damper", "sphere"), "damper"),
        (("reduce", "--damper", "cone", "--modes", "-2"), "modes"),
        (("reduce", "--damper", "cone", "--modes", "twelve"), "modes"),
    ],
)
def test_bad_input_is_one_line_exit_2(tmp_path, args, word):
    r = run_upd(*args, "--out", tmp_path)
    assert r.code == 2, r
    lines = r.err.strip().splitlines()
    assert len(lines) == 1 and word in lines[0] and "Traceback" not in r.err


@pytest.mark.mpi
def test_modes_under_mpirun_matches_serial(tmp_path):
    """``mpirun -n 2 upd modes`` prints one JSON, with the serial frequencies (1e-8)."""
    exe = shutil.which("mpirun")
    assert exe, "mpirun is needed"
    common = ("modes", "--damper", "cone", "--size", "14", "--n", "3", "--no-png", "--json")
    serial = run_upd(*common, "--out", tmp_path / "serial")
    assert serial.code == 0, serial
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", UPD_NO_PROGRESS="1")
    p = subprocess.run(
        [
            exe,
            "-n",
            "2",
            "--allow-run-as-root",
            "--oversubscribe",
            sys.executable,
            "-m",
            "workbench.cli.main",
            *common,
            "--out",
            str(tmp_path / "mpi"),
        ],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=ROOT,
        env=env,
    )
    assert p.returncode == 0, p.stderr[-3000:]
    par = json.loads(p.stdout)  # exactly one JSON document: rank 0 prints
    for a, b in zip(serial.json["freqs_hz"], par["freqs_hz"], strict=True):
        assert b == pytest.approx(a, rel=1e-8, abs=1.5e-3)  # the JSON rounds to 1 mHz

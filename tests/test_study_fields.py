"""Full-mesh peak fields of a study (``--field-shapes``, workbench/studies/engine/fields.py).

Runs on a copy of conftest's tiny study (every case and model reused from
its cache), so only the fields are computed. Checked, after reading the file
back with meshio and pyvista:

* the rig's field at the response point is the curve's own harmonic-1
  peak amplitude (the blade response the study reports);
* damper minus platform at every contact pair, in the pair frame, is the
  relative motion the ``_peak.vtu`` file carries (recovered another way:
  from the contact unknowns directly);
* a second run finds the files current and does not rebuild them.
"""

from __future__ import annotations

import json
import shutil

import meshio
import numpy as np
import pytest
import pyvista as pv

from tests.conftest import TINY, run_upd

# slow (about 3 min of the default run: the field expansion and a 2-rank run): run by
# `make test-slow` with the benchmarks; shares the tiny study of conftest
pytestmark = [pytest.mark.xdist_group("resume"), pytest.mark.slow]


@pytest.fixture(scope="module")
def fields(tiny_resumed, tmp_path_factory):
    out = tmp_path_factory.mktemp("fields") / "tiny"
    shutil.copytree(tiny_resumed[0], out)
    r = run_upd("study", TINY, "--out", out, "--json", "--field-shapes")
    assert r.code == 0, r
    return out, r


def _closest(points: np.ndarray, p: np.ndarray) -> int:
    d = np.linalg.norm(points - p, axis=1)
    i = int(np.argmin(d))
    assert d[i] < 1e-9, d[i]
    return i


def test_field_at_the_response_point_is_the_reported_peak(fields):
    import h5py

    out, _ = fields
    rows = {c["case"]: c for c in json.loads((out / "summary.json").read_text())}
    geo = next((out / "cache" / "geometry").glob("cone-*/geometry.h5"))
    with h5py.File(geo, "r") as h:
        resp = np.asarray(h["response_points"][()])
    for case, row in rows.items():
        p = out / "cases" / f"{case}_peak_field.vtu"
        g = pv.read(p)
        m = meshio.read(p)
        assert len(m.points) == g.n_points and "disp_amp_mm" in m.point_data
        rig = np.asarray(g.point_data["body"]) == 0
        idx = np.flatnonzero(rig)
        j = idx[_closest(np.asarray(g.points)[rig], resp[0])]  # blade 1 (response-blade 1)
        a = np.hypot(g.point_data["disp_cos_mm"][j, 0], g.point_data["disp_sin_mm"][j, 0])
        assert a == pytest.approx(row["h1_amplitude_mm"], rel=1e-6), case
        assert float(g.field_data["force_n"][0]) == row["force_n"]


def test_field_at_the_contacts_is_the_pair_relative_motion(fields):
    out, _ = fields
    for p in sorted((out / "cases").glob("*_peak.vtu")):
        pairs = pv.read(p)
        g = pv.read(str(p).replace("_peak.vtu", "_peak_field.vtu"))
        body = np.asarray(g.point_data["body"])
        pts = np.asarray(g.points)
        rel = []
        for x in np.asarray(pairs.points):
            u = {}
            for b in (0, 1):
                sel = np.flatnonzero(body == b)
                j = sel[_closest(pts[sel], x)]
                u[b] = g.point_data["disp_cos_mm"][j] + 1j * g.point_data["disp_sin_mm"][j]
            rel.append(u[1] - u[0])
        rel = np.array(rel)
        want = pairs.point_data["rel_disp_cos_mm"] + 1j * pairs.point_data["rel_disp_sin_mm"]
        scale = np.abs(want).max()
        assert np.abs(rel - want).max() < 1e-6 * scale, p.name


def test_fields_are_not_rebuilt_when_current(fields, tmp_path):
    out, _ = fields
    before = {p: p.stat().st_mtime_ns for p in (out / "cases").glob("*_peak_field.vtu")}
    assert len(before) == 2
    r = run_upd("study", TINY, "--out", out, "--json", "--field-shapes")
    assert r.code == 0, r
    assert {p: p.stat().st_mtime_ns for p in before} == before


def test_two_ranks_write_the_same_fields_and_exit(fields, tmp_path):
    """Under mpirun every rank takes part in the expansion and the run ends (a rank-0-only
    PETSc session once left the other rank in MPI_Finalize and rank 0 waiting in PETSc's
    garbage clean-up for ever); the fields equal the serial ones body by body."""
    import os
    import subprocess
    import sys

    from scipy.spatial import cKDTree

    from tests.conftest import ROOT

    serial, _ = fields
    out = tmp_path / "mpi"
    shutil.copytree(serial, out)
    for p in (out / "cases").glob("*_peak_field.vtu"):
        p.unlink()
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    mp = subprocess.run(
        ["mpirun", "-n", "2", "--oversubscribe", "-x", "OMP_NUM_THREADS=1"]
        + ["-x", "UPD_NO_PROGRESS=1", sys.executable, "-m", "workbench.cli.main"]
        + ["study", str(TINY), "--out", str(out), "--field-shapes", "-q"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
        env=env,
    )
    assert mp.returncode == 0, mp.stderr[-3000:]
    for p in sorted((serial / "cases").glob("*_peak_field.vtu")):
        a, b = pv.read(p), pv.read(out / "cases" / p.name)
        for body in (0, 1):  # rig and damper share the contact points: match within a body
            ia = np.flatnonzero(np.asarray(a.point_data["body"]) == body)
            ib = np.flatnonzero(np.asarray(b.point_data["body"]) == body)
            d, i = cKDTree(np.asarray(a.points)[ia]).query(np.asarray(b.points)[ib])
            assert d.max() < 1e-12  # every point of the 2-rank file is a mesh node
            for k in ("disp_cos_mm", "disp_sin_mm"):
                va = np.asarray(a.point_data[k])[ia][i]
                vb = np.asarray(b.point_data[k])[ib]
                # the reductions differ by round-off between 1 and 2 ranks
                assert np.abs(va - vb).max() < 1e-8 * np.abs(va).max(), (p.name, body, k)

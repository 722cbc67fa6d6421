"""ParaView-ready output: every VTU/PVD file is read back with meshio and pyvista.

The mesh writer runs on a small second-order box meshed here by gmsh (its
volume is known); modes and the per-case peak files are written from
arrays and read back to the same values (VTU stores float64: exact).
``upd modes`` writes the real files; test_cli_fe reads those back.
"""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

meshio = pytest.importorskip("meshio")
pv = pytest.importorskip("pyvista")

from tests.synthetic import synthetic_case  # noqa: E402
from workbench.io import vtk_out  # noqa: E402


@pytest.fixture(scope="module")
def box_msh(tmp_path_factory) -> Path:
    """A 20 x 10 x 5 mm box of 10-node tetrahedra, two volume groups (0 <= x <= 10, >= 10)."""
    from workbench.geometry.occ import gmsh_session

    p = tmp_path_factory.mktemp("box") / "box.msh"
    with gmsh_session() as gmsh:
        gmsh.model.add("box")
        a = gmsh.model.occ.addBox(0, 0, 0, 0.01, 0.01, 0.005)
        b = gmsh.model.occ.addBox(0.01, 0, 0, 0.01, 0.01, 0.005)
        gmsh.model.occ.fragment([(3, a)], [(3, b)])
        gmsh.model.occ.synchronize()
        gmsh.model.addPhysicalGroup(3, [a], 1)
        gmsh.model.addPhysicalGroup(3, [b], 2)
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.004)
        gmsh.model.mesh.generate(3)
        gmsh.model.mesh.setOrder(2)
        gmsh.write(str(p))
    return p


def test_mesh_vtu_read_by_meshio_and_pyvista(box_msh, tmp_path):
    vtu = vtk_out.write_mesh_vtu(box_msh, tmp_path / "box.vtu")
    m = meshio.read(vtu)
    assert [c.type for c in m.cells] == ["tetra10"]
    assert set(np.unique(m.cell_data["region"][0])) == {1, 2}
    g = pv.read(vtu)
    assert g.n_cells == len(m.cells[0].data) and g.n_points == len(m.points)
    assert set(np.unique(g.celltypes)) == {vtk_out.VTK_QUADRATIC_TETRA}
    # VTK node order of the quadratic tetrahedron: a swapped edge pair would
    # give inverted or twisted cells and a wrong volume
    assert g.volume == pytest.approx(0.02 * 0.01 * 0.005, rel=1e-9)
    assert np.all(g.compute_cell_sizes(length=False, area=False)["Volume"] > 0)


def test_modes_pvd_carry_numbers_and_frequencies(box_msh, tmp_path):
    vtu = vtk_out.write_mesh_vtu(box_msh, tmp_path / "box.vtu")
    g = pv.read(vtu)
    n = g.n_points
    disp = np.stack(
        [np.column_stack([g.points[:, 0] * k, np.zeros(n), np.zeros(n)]) for k in (1.0, 2.0, 3.0)]
    )
    shapes = SimpleNamespace(points=g.points, cells=g.cells, celltypes=g.celltypes, disp=disp)
    freqs = np.array([312.6, 408.1, 950.0])
    pvd = vtk_out.write_modes(tmp_path, "rig", shapes, freqs)
    reader = pv.get_reader(str(pvd))
    assert list(reader.time_values) == [1.0, 2.0, 3.0]  # mode numbers, from 1
    reader.set_active_time_value(2.0)
    block = reader.read()[0]
    np.testing.assert_array_equal(block.point_data["mode_shape"], disp[1])
    assert float(block.field_data["freq_hz"][0]) == 408.1
    m = meshio.read(tmp_path / "modes_rig" / "mode_01.vtu")
    np.testing.assert_array_equal(m.point_data["mode_shape"], disp[0])
    assert float(np.ravel(m.field_data["freq_hz"])[0]) == 312.6
    assert int(np.ravel(m.field_data["mode"])[0]) == 1
    assert "312.600 Hz" in pvd.read_text()


def test_case_peak_file(tmp_path):
    case = synthetic_case("cone", 180.0, 30.0)
    i = case.peak_index
    n = len(case.points)
    frames = np.tile(np.eye(3), (n, 1, 1))
    rel = (np.arange(3 * n).reshape(n, 3) + 1j) * 1e-6
    p = vtk_out.write_case_peak(tmp_path / "c_peak.vtu", case, rel, frames)
    for got in (pv.read(p), meshio.read(p)):
        pd = got.point_data
        np.testing.assert_array_equal(pd["status"], case.branch.status[i])
        np.testing.assert_allclose(pd["friction_energy_mj"], case.energy_mj[i], rtol=0)
        np.testing.assert_allclose(pd["rel_disp_cos_mm"], rel.real * 1e3, rtol=1e-15)
        np.testing.assert_allclose(pd["rel_disp_sin_mm"], -rel.imag * 1e3, rtol=1e-15)
        np.testing.assert_allclose(np.asarray(got.points), case.points, rtol=0)
    assert vtk_out.has_shape(p, case.digest)


def test_peak_relative_motion_matches_the_branch_output():
    """The recovered harmonic-1 contact motion at the peak is the branch's own output there."""
    from workbench.hbm import frequency_response
    from workbench.hbm.io.examples import two_dof_contact

    ex = two_dof_contact()
    b = frequency_response(ex.system, ex.f1, 1.0, ex.band_hz, ex.outputs)
    case = SimpleNamespace(branch=b, peak_index=b.peak(0), phase_deg=0.0)
    rel = vtk_out.peak_relative_motion(case, ex.system)
    # pair frame rows t1, t2, n = x, (none), z of the mass against the ground
    i = case.peak_index
    assert abs(rel[0, 0]) == pytest.approx(b.out_h1[i, 0], rel=1e-9)
    assert abs(rel[0, 2]) == pytest.approx(b.out_h1[i, 1], rel=1e-9)
    assert rel[0, 1] == 0

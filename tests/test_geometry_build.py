"""gmsh builds: node-to-node contact pairs, volumes, groups, files, cache.

Coarse meshes (rig 10 mm, contacts 2.5 mm) keep this fast; the checks do
not depend on the size except the volume convergence, which measures it.
"""

from __future__ import annotations

import math
import os

import numpy as np
import pytest

from workbench.errors import InputError
from workbench.geometry import BuiltGeometry, build_geometry, make_layout
from workbench.geometry.mshio import mesh_file_info, read_tet10
from workbench.geometry.params import load_geometry_params

COARSE = {"rig": {"mesh": {"size_mm": 10.0, "contact_size_mm": 2.5, "damper_size_mm": 5.0}}}
MATCH_M = 1e-9  # the brief's matching tolerance for paired nodes


def coarse(**damper_table):
    out = {"rig": {"mesh": dict(COARSE["rig"]["mesh"])}}
    out.update(damper_table)
    return out


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """One coarse build per damper, shared by the tests of this module."""
    cache = {}

    def get(damper: str) -> BuiltGeometry:
        if damper not in cache:
            out = tmp_path_factory.mktemp(damper)
            cache[damper] = build_geometry(damper, out, overrides=coarse())
        return cache[damper]

    return get


def corner_vertices(msh) -> np.ndarray:
    x, conn = read_tet10(msh)
    return x[np.unique(conn[:, :4])]


@pytest.mark.parametrize("damper", ["cone", "cylinder", "wedge"])
def test_every_contact_point_is_a_vertex_of_both_meshes(built, damper):
    geo = built(damper)
    assert geo.stats["max_pair_gap_m"] <= MATCH_M
    # independently of the stats: nearest tetrahedron corner of each mesh to each point
    from scipy.spatial import cKDTree

    pts = geo.contact.points
    d_rig, i_rig = cKDTree(corner_vertices(geo.rig_msh)).query(pts)
    d_dam, i_dam = cKDTree(corner_vertices(geo.damper_msh)).query(pts)
    assert d_rig.max() <= MATCH_M and d_dam.max() <= MATCH_M
    assert len(np.unique(i_rig)) == len(pts) == len(np.unique(i_dam))  # one node per point
    expected = {"cone": 46, "cylinder": 46, "wedge": 146}[damper]
    assert geo.contact.n_pairs == geo.stats["n_contact_pairs"] == expected
    # excitation and response points are rig vertices too
    named = np.vstack([geo.excitation_points, geo.response_points])
    assert cKDTree(corner_vertices(geo.rig_msh)).query(named)[0].max() <= MATCH_M


def test_cone_contact_nodes_lie_on_the_cone_and_on_their_platform_plane(built):
    """Read the contact node groups back from both files: on the cone and the plane to 1e-9 m."""
    geo = built("cone")
    lay = make_layout(load_geometry_params("cone", overrides=coarse()))
    pl = lay.damper
    apex, a = pl["apex"] * 1e-3, pl["axis"]
    tan_a = math.tan(pl["semi_angle"])
    ridge = np.array([0.0, 0.0, lay.z_ridge * 1e-3])
    for msh in (geo.rig_msh, geo.damper_msh):
        groups = mesh_file_info(msh).point_groups
        for k in range(2):
            p = groups[f"contact_nodes_{k + 1}"]
            assert len(p) == 23
            assert np.abs((p - ridge) @ lay.normals[k]).max() <= MATCH_M  # on platform plane k
            w = p - apex
            ax = w @ a
            rad = np.linalg.norm(w - ax[:, None] * a[None, :], axis=1)
            assert np.abs(rad - ax * tan_a).max() <= MATCH_M  # on the cone surface


@pytest.mark.parametrize("damper", ["cone", "cylinder", "wedge"])
def test_damper_volume_mass_and_centroid(built, damper):
    geo = built(damper)
    exact = geo.stats["damper_volume_exact_m3"]
    # Wedge: flat faces are exact in P2 tetrahedra, what is left is round-off of the
    # mm -> m scaling (~1e-12). Cone and cylinder: the curved surface is a piecewise
    # quadratic interpolation; at a 5 mm damper size on radii of 10-17 mm the measured
    # error is about 1e-5, so 1e-4 is the meshing tolerance.
    tol = 1e-9 if damper == "wedge" else 1e-4
    assert geo.damper_volume_m3 == pytest.approx(exact, rel=tol)
    assert geo.damper_mass_kg == pytest.approx(7800.0 * geo.damper_volume_m3, rel=1e-12)
    # centroid from the mesh against the analytic one (frustum: on the tilted axis)
    c_exact = np.asarray(geo.stats["damper_centroid_exact_m"])
    assert np.linalg.norm(geo.damper_centroid - c_exact) <= (1e-12 if damper == "wedge" else 1e-6)


def test_curved_damper_volume_converges_at_the_rate_of_quadratic_geometry(tmp_path):
    """Halving the damper size cuts the volume error by 2^3 or more (P2 surface, order >= 3)."""
    errs = []
    for h in (6.0, 3.0):
        ov = {
            "rig": {
                "mesh": {
                    "size_mm": 10.0,
                    "contact_size_mm": 6.0,
                    "damper_size_mm": h,
                    "refine_distance_mm": 1.0,
                }
            }
        }
        geo = build_geometry("cylinder", tmp_path / f"h{h}", overrides=ov)
        errs.append(abs(geo.stats["damper_volume_rel_error"]))
    rate = math.log2(errs[0] / errs[1])
    assert rate >= 3.0, (errs, rate)


def test_rig_volume_matches_its_blocks(built):
    geo = built("cone")
    lay = make_layout(load_geometry_params("cone", overrides=coarse()))
    boxes = [lay.base, *lay.blades]
    vol = sum(b.dx * b.dy * b.dz for b in boxes)
    for poly in lay.platform_xz:
        x, z = poly[:, 0], poly[:, 1]
        vol += (
            0.5
            * abs(np.dot(x, np.roll(z, -1)) - np.dot(z, np.roll(x, -1)))
            * (lay.platform_y[1] - lay.platform_y[0])
        )
    # all faces are flat: exact up to the round-off of the mm -> m scaling
    assert mesh_file_info(geo.rig_msh).volume == pytest.approx(vol * 1e-9, rel=1e-9)


def test_physical_groups_in_msh_and_xdmf(built):
    geo = built("wedge")
    rig = mesh_file_info(geo.rig_msh)
    assert set(rig.groups) == {
        "base",
        "blade_1",
        "blade_2",
        "clamped",
        "contact_face_1",
        "contact_face_2",
        "contact_nodes_1",
        "contact_nodes_2",
        "excitation",
        "response",
    }
    dam = mesh_file_info(geo.damper_msh)
    assert set(dam.groups) == {
        "damper",
        "contact_face_1",
        "contact_face_2",
        "contact_nodes_1",
        "contact_nodes_2",
    }
    cone = mesh_file_info(built("cone").damper_msh)
    assert set(cone.groups) == {"damper", "contact_nodes_1", "contact_nodes_2"}
    assert len(rig.point_groups["excitation"]) == 2

    from dolfinx.io import XDMFFile
    from mpi4py import MPI

    with XDMFFile(MPI.COMM_SELF, str(geo.rig_msh.with_suffix(".xdmf")), "r") as f:
        mesh = f.read_mesh(name="rig")
        mesh.topology.create_connectivity(2, 3)
        clamped = f.read_meshtags(mesh, "clamped")
        face1 = f.read_meshtags(mesh, "contact_face_1")
        nodes1 = f.read_meshtags(mesh, "contact_nodes_1")
    x = mesh.geometry.x
    from dolfinx.cpp.mesh import entities_to_geometry

    m = getattr(mesh, "_mesh", mesh)
    g_cl = entities_to_geometry(m, 2, clamped.indices, False)
    assert len(clamped.indices) > 0 and np.abs(x[g_cl.ravel(), 2]).max() < 1e-12  # base bottom
    lay = make_layout(load_geometry_params("wedge", overrides=coarse()))
    g_f1 = entities_to_geometry(m, 2, face1.indices, False).ravel()
    ridge = np.array([0.0, 0.0, lay.z_ridge * 1e-3])
    assert np.abs((x[g_f1] - ridge) @ lay.normals[0]).max() < MATCH_M
    assert len(nodes1.indices) == 73


def test_read_msh_gives_a_dolfinx_mesh_with_the_contact_vertices(built):
    from workbench.geometry import read_msh

    geo = built("cylinder")
    d = read_msh(geo.damper_msh)
    assert d.groups["damper"] == (3, 1)
    assert set(np.unique(d.cell_tags.values)) == {1}
    from scipy.spatial import cKDTree

    assert cKDTree(d.mesh.geometry.x).query(geo.contact.points)[0].max() <= MATCH_M
    r = read_msh(geo.rig_msh)
    assert set(np.unique(r.cell_tags.values)) == {1, 2, 3}
    assert {r.groups[n][1] for n in ("clamped", "contact_face_1", "contact_face_2")} == set(
        np.unique(r.facet_tags.values)
    )


def test_record_roundtrip_and_cache(tmp_path):
    ov = coarse()
    geo = build_geometry("cylinder", tmp_path, overrides=ov)
    h5 = tmp_path / "geometry.h5"
    stamp = {p.name: p.stat().st_mtime_ns for p in tmp_path.iterdir()}
    again = build_geometry("cylinder", tmp_path, overrides=ov)  # same inputs: reused
    assert {p.name: p.stat().st_mtime_ns for p in tmp_path.iterdir()} == stamp
    loaded = BuiltGeometry.load(h5)
    for rec in (again, loaded):
        assert rec.digest == geo.digest
        assert np.array_equal(rec.contact.points, geo.contact.points)
        assert np.array_equal(rec.contact.frames, geo.contact.frames)
        assert rec.stats["n_nodes"] == geo.stats["n_nodes"]
        assert rec.params == geo.params
    # a changed input rebuilds (new digest, new record)
    ov["cylinder"] = {"radius_mm": 12.0}
    other = build_geometry("cylinder", tmp_path, overrides=ov)
    assert other.digest != geo.digest
    assert BuiltGeometry.load(h5).digest == other.digest
    # a deleted mesh file is rebuilt even though the record is there
    os.unlink(tmp_path / "damper.msh")
    rebuilt = build_geometry("cylinder", tmp_path, overrides=ov)
    assert rebuilt.damper_msh.is_file() and rebuilt.digest == other.digest


def test_bad_input_never_reaches_gmsh(tmp_path):
    with pytest.raises(InputError) as e:
        build_geometry("cone", tmp_path, overrides={"cone": {"semi_angle_deg": 50.0}})
    assert e.value.param == "cone.semi_angle_deg"
    with pytest.raises(InputError) as e:
        build_geometry("cone", tmp_path, size_mm=-1.0)
    assert e.value.param == "size_mm"
    assert not any(tmp_path.iterdir())  # nothing written

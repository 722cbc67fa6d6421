"""Mirror-image meshes (``[rig.mesh] mirror``): the half x >= 0 meshed and mirrored.

The rig, the dampers and their contact points are symmetric about x = 0. With the option
the two halves of each mesh are exact mirror images (every node's image is a node), the
volume and the physical groups are those of a whole build, every element keeps a positive
orientation, and the elastic model inherits the symmetry: the static compliance of the
rig's interface nodes (Craig-Bampton, base clamped) is invariant under the mirror to
round-off, where a whole mesh misses it by the discretisation's asymmetry.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

from workbench.geometry import build_geometry
from workbench.geometry.mshio import mesh_file_info
from workbench.geometry.occ import gmsh_session

COARSE = {"rig": {"mesh": {"size_mm": 14.0, "contact_size_mm": 4.0}}}
POINTS = {"cone": {"n_contact_points": 5}, "cylinder": {"n_contact_points": 5}, "wedge": {}}
MIRROR = np.array([-1.0, 1.0, 1.0])


def _build(damper: str, mirror: bool, out):
    ov = {"rig": {"mesh": dict(COARSE["rig"]["mesh"], mirror=mirror)}, damper: POINTS[damper]}
    return build_geometry(damper, out, overrides=ov)


def _min_jacobian(path) -> float:
    with gmsh_session() as gmsh:
        gmsh.open(str(path))
        _, det, _ = gmsh.model.mesh.getJacobians(11, [0.25, 0.25, 0.25])
        return float(np.min(det))


@pytest.mark.parametrize("damper", ["cone", "cylinder", "wedge"])
def test_a_mirrored_build_is_its_own_mirror_image(damper, tmp_path):
    mirrored = _build(damper, True, tmp_path / "m")
    whole = _build(damper, False, tmp_path / "w")
    for body in ("rig", "damper"):
        m = mesh_file_info(getattr(mirrored, f"{body}_msh"))
        w = mesh_file_info(getattr(whole, f"{body}_msh"))
        # every corner node's mirror image is a corner node (to round-off)
        dist, _ = cKDTree(m.vertices).query(m.vertices * MIRROR)
        assert dist.max() < 1e-12, body
        # a whole mesh is not (the test can fail)
        dist_w, _ = cKDTree(w.vertices).query(w.vertices * MIRROR)
        assert dist_w.max() > 1e-5, body
        # the same body: volume (exact for the rig's planes, to the curved faces' second-order
        # interpolation for a cone or cylinder), groups, contact points
        rel = 1e-12 if body == "rig" or damper == "wedge" else 1e-5
        assert m.volume == pytest.approx(w.volume, rel=rel), body
        assert m.groups == w.groups, body
        for name, pts in w.point_groups.items():
            got = m.point_groups[name]
            assert got.shape == pts.shape, (body, name)
            assert cKDTree(got).query(pts)[0].max() < 1e-12, (body, name)
        c1, c2 = m.point_groups["contact_nodes_1"], m.point_groups["contact_nodes_2"]
        assert cKDTree(c2).query(c1 * MIRROR)[0].max() < 1e-12, body
        assert _min_jacobian(getattr(mirrored, f"{body}_msh")) > 0.0, body
    # the contact pairs still match node to node
    assert mirrored.stats["max_pair_gap_m"] <= 1e-9


def _mirror_error(geom, tmp_path) -> float:
    """|C - P C P^T| / |C|: C the static compliance of the rig's contact nodes (base
    clamped), P the mirror (each node to its image, x reversed)."""
    from workbench.fe.reduce import reduce_body

    rig = reduce_body(geom, "rig", n_modes=4, cache_dir=tmp_path)
    nodes = np.asarray(rig.node_sets["contact"])
    x = rig.node_coords[nodes]
    _, image = cKDTree(x).query(x * MIRROR)
    assert np.array_equal(np.sort(image), np.arange(len(nodes)))
    G = rig.T[rig.node_dofs(nodes)]
    C = G @ np.linalg.solve(rig.K, G.T)
    P = np.zeros_like(C)
    for i, j in enumerate(image):
        P[3 * j : 3 * j + 3, 3 * i : 3 * i + 3] = np.diag(MIRROR)
    return float(np.linalg.norm(C - P @ C @ P.T) / np.linalg.norm(C))


def test_the_mirrored_rigs_compliance_is_symmetric(tmp_path):
    """To round-off on the mirror mesh (1e-9; the Cholesky solve's), not on the whole one."""
    sym = _mirror_error(_build("cone", True, tmp_path / "m"), tmp_path / "fe_m")
    asym = _mirror_error(_build("cone", False, tmp_path / "w"), tmp_path / "fe_w")
    assert sym < 1e-9
    assert asym > 1e-4


def test_a_disk_sector_takes_a_mirrored_damper(tmp_path):
    """The bladed disk's sector has no mirror plane and is meshed whole; its damper is the
    rig's damper mesh, mirrored like any other: the sector builds, its pairs match node to
    node (the builder checks), as many as with a whole damper mesh, and the damper's mesh
    differs from the whole one."""
    from tests.test_disk import COARSE as DISK_COARSE
    from tests.test_disk import PAPER
    from workbench.geometry.disk_build import build_disk_sector

    def sector(mirror: bool, out):
        over = {**DISK_COARSE, "rig": {"mesh": dict(DISK_COARSE["rig"]["mesh"], mirror=mirror)}}
        return build_disk_sector("cylinder", out, geometry_file=PAPER, n_blades=6, overrides=over)

    m, w = sector(True, tmp_path / "m"), sector(False, tmp_path / "w")
    assert m.contact.n_pairs == w.contact.n_pairs > 0
    dm, dw = mesh_file_info(m.damper_msh), mesh_file_info(w.damper_msh)
    # the same body: its curved face is interpolated to second order by either mesh (at this
    # coarse damper size, 10 mm, they differ by 3e-5 of the volume)
    assert dm.volume == pytest.approx(dw.volume, rel=1e-4) and dm.n_nodes != dw.n_nodes


def test_on_mirror_meshes_the_cone_in_phase_splits_its_energy_evenly(tmp_path):
    """A real (coarse) study of the cone in phase at 30 N on the paper rig: on mirror meshes
    each line dissipates half the energy to the solver's tolerance; on whole meshes the
    split is the mesh's (5.6 % here)."""
    from tests.conftest import ROOT, run_upd
    from workbench.post.results import StudyResults

    paper = (ROOT / "geometry" / "paper_rig.toml").read_text()
    assert paper.count("\nmirror = true ") == 1  # the paper rig runs on mirror meshes
    files = {}
    for name in ("mirror", "whole"):
        files[name] = tmp_path / f"{name}.toml"
        flag = "true" if name == "mirror" else "false"
        files[name].write_text(paper.replace("\nmirror = true ", f"\nmirror = {flag} "))
    study = tmp_path / "s.toml"
    study.write_text(
        'name = "split"\ndampers = ["cone"]\nphases = [0.0]\nforces = [30.0]\n'
        "mesh-size = 14.0\ncontact-mesh-size = 4.0\npoints-per-line = 7\nmodes = 6\n"
        "stability = false\n"
    )
    split = {}
    for name, geometry in files.items():
        r = run_upd("study", study, "--geometry", geometry, "--out", tmp_path / name)
        assert r.code == 0, r
        (case,) = StudyResults.load(tmp_path / name / "results.h5").cases
        split[name] = case.energy_split_pct()
        # the record (and so the report's inputs) says which mesh it was, and from where
        rec = case.inputs["mirror_meshes"]
        assert rec["value"] is (name == "mirror")
        assert rec["source"].endswith("[rig.mesh]")
        assert f"{name}.toml" in rec["source"]
        assert case.inputs["contact_pads"]["value"] == 0.0
        assert case.inputs["contact_mesh_size"]["value"] == 4.0
    assert abs(split["mirror"]) < 1e-3
    assert abs(split["whole"]) > 1.0

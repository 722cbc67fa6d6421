"""Contact pads (workbench/fe/pads.py): a point load's compliance diverges, a pad's converges.

* the pad penalty annihilates exactly the rigid motions of the pad's nodes;
* the pad of a line pair spans its tributary length (times FILL) along the
  line and half the width across and in depth;
* on a clamped beam, the static compliance under a point on the beam's face
  grows without limit as the mesh is refined (a point load on an elastic
  body), while under a rigid pad of fixed size it converges;
* a free block keeps exactly six rigid-body modes with pads tied.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sl

from workbench.fe.craig_bampton import craig_bampton
from workbench.fe.elasticity import Material, assemble_body
from workbench.fe.interface import locate_nodes
from workbench.fe.mesh import read_msh
from workbench.fe.pads import FILL, pad_members, rigid_penalty, tie_pads
from workbench.fe.samples import STEEL, beam_msh, block_msh
from workbench.geometry.records import ContactSet

MAT = Material.from_dict(STEEL)


def _rigid(r, t, th):
    return np.concatenate([t + np.cross(th, x) for x in r])


def test_rigid_penalty_annihilates_rigid_motions_only():
    rng = np.random.default_rng(0)
    r = rng.normal(size=(7, 3))
    P = rigid_penalty(r)
    u = _rigid(r, np.array([1.0, -2.0, 0.5]), np.array([0.3, 0.1, -0.2]))
    assert np.abs(P @ u).max() < 1e-12 * np.abs(u).max()
    assert np.linalg.matrix_rank(P) == 3 * 7 - 6
    v = rng.normal(size=21)
    assert v @ P @ v > 0  # a deformation costs energy


@pytest.mark.parametrize("k", [2, 3, 5])
def test_a_pad_on_one_line_ties_all_but_its_five_rigid_motions(k):
    """Nodes on one line (a two-node pad, or a coarse pad whose nodes lie on the contact
    line) have five rigid motions: the rotation about the line moves none of them. The
    penalty annihilates every rigid motion, rotation about the line included, penalises
    the other 3 k - 5 directions (a stretch along the line among them), and ties a pad
    and its mirror image alike (a plain QR of the rank-deficient basis tied two-node pads
    not at all and mirror images differently)."""
    x = np.linspace(0.0, 1e-3 * (k - 1), k) + 0.3e-3 * np.arange(k) ** 2  # uneven spacing
    d = np.array([0.6, -0.3, 0.74])
    d /= np.linalg.norm(d)
    r = np.outer(x - x.mean(), d)
    P = rigid_penalty(r)
    assert np.linalg.matrix_rank(P, 1e-9) == 3 * k - 5
    for t, th in ((np.array([1.0, -2.0, 0.5]), np.array([0.3, 0.1, -0.2])), (np.zeros(3), d)):
        u = _rigid(r, t, th)
        assert np.abs(P @ u).max() < 1e-9 * max(np.abs(u).max(), 1e-3)
    stretch = np.concatenate([xi * d for xi in x - x.mean()])
    assert stretch @ P @ stretch > 0.5 * stretch @ stretch  # a deformation costs energy
    mirror = np.kron(np.eye(k), np.diag([-1.0, 1.0, 1.0]))
    Pm = rigid_penalty(r * np.array([-1.0, 1.0, 1.0]))
    assert np.abs(Pm - mirror @ P @ mirror).max() < 1e-9


def test_line_pad_members():
    """Nodes on a grid around three points on a line along x, spacing 2 mm, normal z."""
    g = np.arange(-5, 5.01, 0.5) * 1e-3
    X, Y, Z = np.meshgrid(g, g, g, indexing="ij")
    coords = np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])
    pts = np.array([[-2e-3, 0, 0], [0, 0, 0], [2e-3, 0, 0]])
    frames = np.tile(np.array([[0.0, 1, 0], [1, 0, 0], [0, 0, 1]]), (3, 1, 1))
    members = pad_members(coords, pts, frames, np.full(3, 2e-3), "line", 2e-3)
    mid = coords[members[1]]
    assert np.abs(mid[:, 0]).max() <= 0.5 * FILL * 2e-3 + 1e-15
    assert np.linalg.norm(mid[:, 1:], axis=1).max() <= 1e-3 + 1e-15
    # the grid has nodes at x = -0.5, 0, 0.5 mm and 13 of them within 1 mm of the axis
    # (the contact node itself left out)
    assert len(mid) == 3 * 13 - 1
    assert not set(members[0]) & set(members[1])  # neighbouring pads never share a node


def _beam_compliance(tmp_path, lc, pad):
    p = (0.01, 0.01, 0.1)  # on the face x = thickness, mid width, mid span
    path = beam_msh(tmp_path / f"beam_{lc}.msh", lc=lc, points=[p])
    body = assemble_body(read_msh(path), MAT, name="beam", clamped="clamped")
    nodes = locate_nodes(body, np.array([p]))
    if pad:
        # a face pair with normal x and a 4 mm x 4 mm tributary square (the pad: 3.6 mm)
        cs = ContactSet(
            points=np.array([p]),
            frames=np.array([[[0.0, 1, 0], [0.0, 0, 1], [1.0, 0, 0]]]),
            side=np.zeros(1, dtype=int),
            weight=np.array([16e-6]),
            kind="face",
        )
        tie_pads(body, nodes, cs, pad)
    cb = craig_bampton(body, nodes, 0)
    return float(np.linalg.inv(cb.K)[0, 0])  # m/N along the face normal


def test_point_load_diverges_pad_converges(tmp_path):
    """Refining 4 -> 2.8 -> 2 mm: a point's compliance keeps growing, by more each step
    in proportion (1/h); under a 3.6 mm rigid pad the steps shrink (measured 1.2e-11,
    3.3e-12 m/N: a factor 3.6 for a factor 1.4 in h), and the pad's compliance lies below
    the point's."""
    hs = (0.004, 0.0028, 0.002)
    g0 = [_beam_compliance(tmp_path, h, 0.0) for h in hs]
    g1 = [_beam_compliance(tmp_path, h, 0.002) for h in hs]
    d0 = np.diff(g0)
    d1 = np.diff(g1)
    assert np.all(d0 > 0) and d0[1] > 0.8 * d0[0]  # not converging
    assert abs(d1[1]) < 0.5 * abs(d1[0])  # converging
    assert np.all(np.array(g1) < np.array(g0))


def test_free_block_with_pads_keeps_six_rigid_modes(tmp_path):
    """Three pads on a line on the face x = 0 (interface: those three points and three more
    on the other faces, so the fixed-interface block has no mechanism)."""
    line = [[0.0, y, 0.005] for y in (0.004, 0.008, 0.012)]
    pts = np.array(line + [[0.02, 0.004, 0.005], [0.02, 0.012, 0.005], [0.01, 0.008, 0.01]])
    path = block_msh(tmp_path / "block.msh", size=(0.02, 0.016, 0.01), lc=0.002, points=pts)
    body = assemble_body(read_msh(path), MAT, name="damper")
    nodes = locate_nodes(body, pts)
    cs = ContactSet(
        points=pts[:3],
        frames=np.tile(np.array([[0.0, 0, 1], [0.0, 1, 0], [-1.0, 0, 0]]), (3, 1, 1)),
        side=np.zeros(3, dtype=int),
        weight=np.full(3, 0.004),
        kind="line",
    )
    counts = tie_pads(body, nodes, cs, 0.003)
    assert counts["pad_nodes"] > 3
    cb = craig_bampton(body, nodes, 6)
    lam = sl.eigh(cb.K, cb.M, eigvals_only=True)
    assert np.all(np.abs(lam[:6]) < 1e-8 * lam[6])
    assert lam[6] > 0


def test_no_pad_no_members():
    """Width 0: no pad, the contact node alone (the default)."""
    coords = np.zeros((4, 3))
    out = pad_members(coords, np.zeros((1, 3)), np.eye(3)[None], np.ones(1), "line", 0.0)
    assert len(out) == 1 and len(out[0]) == 0


def test_pad_variant_of_the_paper_rig_keeps_in_step():
    """geometry/paper_rig_pads.toml is geometry/paper_rig.toml with pads and the contact
    stiffness scaled by the calibration its header states; nothing else differs."""
    import tomllib
    from pathlib import Path

    root = Path(__file__).resolve().parents[1] / "geometry"
    base = tomllib.loads((root / "paper_rig.toml").read_text())
    pads = tomllib.loads((root / "paper_rig_pads.toml").read_text())
    assert pads["rig"].pop("mesh") == {"pad_mm": 2.0, **base["rig"].pop("mesh")}
    cb, cp = base.pop("contact"), pads.pop("contact")
    assert pads == base
    for key, scale in (("kt_line_n_per_m2", 0.4509), ("kn_line_n_per_m2", 0.4509),
                       ("kt_face_n_per_m3", 0.9253), ("kn_face_n_per_m3", 0.9253)):  # fmt: skip
        assert cp.pop(key) == pytest.approx(scale * cb.pop(key), rel=1e-3)
    assert cp == cb

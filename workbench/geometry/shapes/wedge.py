"""The wedge damper: a prism along y whose two upper faces lie on the platform planes.

Parameters (``geometry/wedge.toml``, table ``[wedge]``), seating in the
groove (contact over two faces, rows of points up each slope, staggered),
the parameters named when it does not fit, and its gmsh drawing (an
extruded section); registered as ``SHAPE`` (see
:mod:`workbench.geometry.shapes`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...config import param
from ..seat_tools import SAME_MM, check_step, fit_error, voronoi_1d
from . import DamperShape


@dataclass(frozen=True)
class WedgeParams:
    """Wedge damper: a prism along y whose two upper faces lie on the platform planes."""

    length_mm: float = param(40.0, "length along y, mm", lo=0.0, lo_open=True)
    top_width_mm: float = param(
        12.0,
        "width (along x) of the flat top between the two contact faces, mm",
        lo=0.0,
        lo_open=True,
    )
    face_width_mm: float = param(
        10.0, "width of each contact face measured down its slope, mm", lo=0.0, lo_open=True
    )
    skirt_height_mm: float = param(
        4.0, "height of the vertical sides below the contact faces, mm", lo=0.0
    )
    n_contact_rows: int = param(5, "rows of contact points up each face's slope", lo=2, hi=100)
    n_contact_per_row: int = param(
        15,
        "contact points in a full row along y (rows alternate n and n - 1: staggered)",
        lo=2,
        hi=200,
    )


def seat(p: WedgeParams, g: dict, rig: Any = None) -> dict:
    """The prism's contact faces are the strips ``s_a <= sigma <= s_b`` of the two planes,
    ``s_a = (top_width / 2) / sin beta``; rows of points up each face, staggered. Keys as
    :func:`.cylinder.seat`."""
    beta = g["beta"]
    sb = math.sin(beta)
    L, ny, ns_rows = p.length_mm, p.n_contact_per_row, p.n_contact_rows
    s_a = (p.top_width_mm / 2) / sb
    s_b = s_a + p.face_width_mm
    ridge = np.array([0.0, 0.0, g["z_ridge"]])
    up1 = ridge + s_a * g["down"][0]
    lo1 = ridge + s_b * g["down"][0]
    skirt = p.skirt_height_mm if p.skirt_height_mm >= SAME_MM else 0.0
    z_bot = lo1[2] - skirt
    # section polygon in the x-z plane, counter-clockwise seen from +y... order is irrelevant
    poly = np.array(
        [
            [up1[0], up1[2]],
            [lo1[0], lo1[2]],
            [lo1[0], z_bot],
            [-lo1[0], z_bot],
            [-lo1[0], lo1[2]],
            [-up1[0], up1[2]],
        ]
    )
    if skirt == 0.0:
        poly = np.delete(poly, [2, 3], axis=0)
    f = g["min_feature"]
    check_step(
        "wedge.skirt_height_mm",
        p.skirt_height_mm,
        p.skirt_height_mm,
        f,
        "the height of the wedge's vertical sides",
    )
    if p.face_width_mm < f:
        raise fit_error(
            "wedge.face_width_mm",
            p.face_width_mm,
            f"wedge.face_width_mm >= rig.fit.min_feature_mm = {f:g} mm",
            "the contact faces would be slivers",
        )
    h = p.face_width_mm / ns_rows
    rows_s = s_b - (np.arange(ns_rows) + 0.5) * h  # row 0 lowest, up the slope
    full_y = -L / 2 + (np.arange(ny) + 0.5) * L / ny
    short_y = -L / 2 + (np.arange(1, ny)) * L / ny
    pts, t1s, ns, side, weight = [], [], [], [], []
    for k in range(2):
        for j, sj in enumerate(rows_s):
            ys = full_y if j % 2 == 0 else short_y
            w = voronoi_1d(ys, -L / 2, L / 2) * h
            base_pt = ridge + sj * g["down"][k]
            pts.append(base_pt[None, :] + ys[:, None] * np.array([0.0, 1.0, 0.0]))
            t1s.append(np.tile([0.0, 1.0, 0.0], (len(ys), 1)))
            ns.append(np.tile(g["normals"][k], (len(ys), 1)))
            side.append(np.full(len(ys), k))
            weight.append(w)
    x, z = poly[:, 0], poly[:, 1]
    xs, zs = np.roll(x, -1), np.roll(z, -1)
    cross = x * zs - xs * z
    area = 0.5 * cross.sum()
    cx = ((x + xs) * cross).sum() / (6 * area)
    cz = ((z + zs) * cross).sum() / (6 * area)
    ends = []
    for k in range(2):
        for s_ in (s_a, s_b):
            for yy in (-L / 2, L / 2):
                ends.append(ridge + s_ * g["down"][k] + np.array([0.0, yy, 0.0]))
    return dict(
        placement=dict(kind="wedge", section_xz=poly, y0=-L / 2, length=L, s_a=s_a, s_b=s_b),
        points=np.vstack(pts),
        t1=np.vstack(t1s),
        n=np.vstack(ns),
        side=np.concatenate(side),
        weight=np.concatenate(weight),
        kind="face",
        extent=p.face_width_mm * L,
        line_ends=np.array(ends),
        volume=abs(area) * L,
        centroid=np.array([cx, 0.0, cz]),
        x_extent=float(np.abs(poly[:, 0]).max()),
        z_min=float(poly[:, 1].min()),
        notes=dict(
            contact_face_area_mm2=p.face_width_mm * L,
            points_per_face=int(sum(ny if j % 2 == 0 else ny - 1 for j in range(ns_rows))),
        ),
    )


def fit_blame(gp: Any, g: dict, pl: dict, lo_ok: float, hi_ok: float, half_w: float):
    """The top width when the faces start above the platform tip, the face width when they
    reach below its root, the length when they run off its width."""
    sb = math.sin(g["beta"])
    small = (
        "wedge.top_width_mm",
        gp.shape.top_width_mm,
        f"wedge.top_width_mm >= {2 * lo_ok * sb:.4g} mm",
    )
    large = (
        "wedge.face_width_mm",
        gp.shape.face_width_mm,
        f"wedge.face_width_mm <= {hi_ok - pl['s_a']:.4g} mm",
    )
    long_ = ("wedge.length_mm", pl["length"], f"wedge.length_mm <= {2 * half_w:.4g} mm")
    return small, large, long_


def hit_blame(gp: Any, g: dict, pl: dict, x_max: float):
    """The face width, when the wedge would touch the blades."""
    sb = math.sin(g["beta"])
    return (
        "wedge.face_width_mm",
        gp.shape.face_width_mm,
        f"wedge.face_width_mm <= {max(x_max / sb - pl['s_a'], 0.0):.4g} mm",
    )


def draw(gmsh: Any, lay: Any, members: dict, point_tags: list) -> int:
    """The section extruded along y; the contact points embedded in the two contact faces
    (mirrored, ``[rig.mesh] mirror``: its half x >= 0 and side 2's face only)."""
    from ..occ import embed_points, face_containing, sides

    occ = gmsh.model.occ
    pl = lay.damper
    sec = pl["section_xz"]
    corners = [occ.addPoint(float(x), pl["y0"], float(z)) for x, z in sec]
    lines = [occ.addLine(corners[i], corners[(i + 1) % len(corners)]) for i in range(len(corners))]
    face = occ.addPlaneSurface([occ.addCurveLoop(lines)])
    ext = occ.extrude([(2, face)], 0.0, pl["length"], 0.0)
    occ.synchronize()
    vol = [t for d, t in ext if d == 3][0]
    if lay.params.rig.mesh.mirror:
        from ..mirror import keep_half

        (vol,) = keep_half(gmsh, [(3, vol)])
    for k in sides(lay):
        pts = lay.points[lay.side == k]
        f = face_containing(gmsh, lay.normals[k], pts, f"wedge contact face {k + 1}")
        members[f"contact_face_{k + 1}"] = [f]
        tags = embed_points(gmsh, pts, f)
        members[f"contact_nodes_{k + 1}"] = tags
        point_tags += tags
    return vol


SHAPE = DamperShape(
    name="wedge",
    params=WedgeParams,
    contact="face",
    seat=seat,
    fit_blame=fit_blame,
    hit_blame=hit_blame,
    draw=draw,
    style=("#009E73", "-.", "^"),  # Okabe-Ito bluish green (render/palette.py)
    order=3,
    description="a prism along y, contact over one face on each platform",
)

"""The cylindrical damper: a cylinder along y touching each platform plane along a line.

Parameters (``geometry/cylinder.toml``, table ``[cylinder]``), seating in
the groove, the parameters named when it does not fit, and its gmsh
drawing; registered as ``SHAPE`` (see :mod:`workbench.geometry.shapes`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...config import param
from . import DamperShape


@dataclass(frozen=True)
class CylinderParams:
    """Cylindrical damper, axis along y."""

    radius_mm: float = param(13.5265, "radius R, mm", lo=0.0, lo_open=True)
    length_mm: float = param(40.0, "length L along y, mm", lo=0.0, lo_open=True)
    n_contact_points: int = param(23, "contact points per contact line", lo=2, hi=400)


def seat(p: CylinderParams, g: dict, rig: Any = None) -> dict:
    """Axis on x = 0 at ``z_ridge - R / sin beta``; contact generators at ``c - R n[k]``.

    Returns ``placement`` (what gmsh draws), the contact ``points`` with
    their tangent ``t1`` and normal ``n``, ``side`` (0, 1), ``weight``
    (tributary length, mm), ``kind``, ``extent`` (line length), the four
    ``line_ends``, the analytic ``volume`` and ``centroid``, ``x_extent``
    and ``z_min`` (for the clearance checks) and ``notes``.
    """
    beta, R, L, n = g["beta"], p.radius_mm, p.length_mm, p.n_contact_points
    sb = math.sin(beta)
    zc = g["z_ridge"] - R / sb
    c = np.array([0.0, 0.0, zc])
    y = -L / 2 + (np.arange(n) + 0.5) * L / n
    pts, t1s, ns, side = [], [], [], []
    for k in range(2):
        foot = c - R * g["normals"][k]
        pts.append(foot[None, :] + y[:, None] * np.array([0.0, 1.0, 0.0]))
        t1s.append(np.tile([0.0, 1.0, 0.0], (n, 1)))
        ns.append(np.tile(g["normals"][k], (n, 1)))
        side.append(np.full(n, k))
    ends = [
        (c - R * g["normals"][k]) + s * np.array([0.0, L / 2, 0.0])
        for k in range(2)
        for s in (-1.0, 1.0)
    ]
    return dict(
        placement=dict(
            kind="cylinder", center=c, axis=np.array([0.0, 1.0, 0.0]), radius=R, length=L, y0=-L / 2
        ),
        points=np.vstack(pts),
        t1=np.vstack(t1s),
        n=np.vstack(ns),
        side=np.concatenate(side),
        weight=np.full(2 * n, L / n),
        kind="line",
        extent=L,
        line_ends=np.array(ends),
        volume=math.pi * R * R * L,
        centroid=c.copy(),
        x_extent=R,
        z_min=zc - R,
        notes=dict(contact_line_length_mm=L),
    )


def fit_blame(gp: Any, g: dict, pl: dict, lo_ok: float, hi_ok: float, half_w: float):
    """The radius when the lines run off the inclined face, the length when off its width."""
    sb, cb = math.sin(g["beta"]), math.cos(g["beta"])
    r_lo, r_hi = lo_ok * sb / cb, hi_ok * sb / cb
    rng = f"{r_lo:.4g} <= cylinder.radius_mm <= {r_hi:.4g} mm"
    small, large = (
        ("cylinder.radius_mm", pl["radius"], rng),
        ("cylinder.radius_mm", pl["radius"], rng),
    )
    long_ = ("cylinder.length_mm", pl["length"], f"cylinder.length_mm <= {2 * half_w:.4g} mm")
    return small, large, long_


def hit_blame(gp: Any, g: dict, pl: dict, x_max: float):
    """The radius, when the cylinder would touch the blades."""
    return ("cylinder.radius_mm", pl["radius"], f"cylinder.radius_mm <= {x_max:.4g} mm")


def draw(gmsh: Any, lay: Any, members: dict, point_tags: list) -> int:
    """The cylinder, its seam turned down, the contact points embedded in its lateral face."""
    from ..occ import embed_on_lateral_face

    occ = gmsh.model.occ
    pl = lay.damper
    c = pl["center"]
    vol = occ.addCylinder(0.0, pl["y0"], float(c[2]), 0.0, pl["length"], 0.0, pl["radius"])
    origin, axis = np.array([0.0, pl["y0"], c[2]]), np.array([0.0, 1.0, 0.0])
    return embed_on_lateral_face(gmsh, lay, vol, origin, axis, "Cylinder", members, point_tags)


SHAPE = DamperShape(
    name="cylinder",
    params=CylinderParams,
    contact="line",
    seat=seat,
    fit_blame=fit_blame,
    hit_blame=hit_blame,
    draw=draw,
    style=("#CC79A7", "--", "s"),  # Okabe-Ito reddish purple (render/palette.py)
    study_options={"points-per-line": ("n_contact_points", int)},
    order=2,
    description="a cylinder along y, one contact line on each platform",
)

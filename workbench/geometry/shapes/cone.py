"""The conical damper (the paper's new geometry): a frustum touching each platform along a line.

Parameters (``geometry/cone.toml``, table ``[cone]``), seating in the
groove (its axis tilts by gamma in the y-z plane so that both generators
lie on the platform planes), the parameters named when it does not fit,
and its gmsh drawing; registered as ``SHAPE`` (see
:mod:`workbench.geometry.shapes`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...config import param
from ...errors import InputError
from . import DamperShape


@dataclass(frozen=True)
class ConeParams:
    """Conical damper: a frustum whose axis tilts by gamma in the y-z plane."""

    semi_angle_deg: float = param(
        10.0,
        "cone semi-angle alpha_c (must be below the platform angle), deg",
        lo=0.0,
        hi=75.0,
        lo_open=True,
    )
    r1_mm: float = param(10.0, "radius of the small end R1, mm", lo=0.0, lo_open=True)
    length_mm: float = param(
        40.0, "length L along the cone axis (R2 = R1 + L tan alpha_c), mm", lo=0.0, lo_open=True
    )
    n_contact_points: int = param(23, "contact points per contact line", lo=2, hi=400)


def _cone_large(name: str, pl: dict, l_hi: float, r2_hi: float) -> tuple[str, float, str]:
    """The parameter to blame when the cone's large end does not fit: its length, or, when
    even the small radius is too large for any length, ``cone.r1_mm``."""
    if l_hi <= 0.0:
        return (
            "cone.r1_mm",
            pl["r1"],
            f"cone.r1_mm < {r2_hi:.4g} mm (the large radius "
            f"R2 = R1 + L tan(alpha_c) must stay <= {r2_hi:.4g} mm)",
        )
    return (name, pl["length"], f"{name} <= {l_hi:.4g} mm (large radius R2 <= {r2_hi:.4g} mm)")


def seat(p: ConeParams, g: dict, rig: Any) -> dict:
    """The apex on the ridge, the axis in the y-z plane tilted by ``gamma`` with
    ``sin gamma = sin alpha_c / sin beta``, large end at -y and lower; the generator in plane
    k is ``(a - sin alpha_c n[k]) / cos alpha_c``. Keys as :func:`.cylinder.seat`."""
    beta = g["beta"]
    ac = math.radians(p.semi_angle_deg)
    if ac >= beta:
        raise InputError(
            "cone.semi_angle_deg",
            p.semi_angle_deg,
            f"0 < cone.semi_angle_deg < rig.platform.angle_deg = {rig.platform.angle_deg:g} deg",
            "a cone touches both platform planes along generators only if its axis tilts by "
            "gamma with sin(gamma) = sin(alpha_c) / sin(beta); for alpha_c >= beta that has no "
            "solution (at alpha_c = beta the cone would stand vertical)",
        )
    sb, sa, ca = math.sin(beta), math.sin(ac), math.cos(ac)
    gamma = math.asin(sa / sb)
    cg, sg = math.cos(gamma), math.sin(gamma)
    R1, L, n = p.r1_mm, p.length_mm, p.n_contact_points
    R2 = R1 + L * math.tan(ac)
    a = np.array([0.0, -cg, -sg])  # unit axis, apex -> large end
    s1, s2 = R1 / sa, R2 / sa  # slant distances apex -> small / large end
    sm = 0.5 * (s1 + s2)
    apex = np.array([0.0, sm * cg / ca, g["z_ridge"]])  # contact lines centred on y = 0
    h1, h2 = R1 / math.tan(ac), R2 / math.tan(ac)
    c1, c2 = apex + h1 * a, apex + h2 * a  # small-end and large-end centres
    s = s2 - (np.arange(n) + 0.5) * (s2 - s1) / n  # large end -> small end
    pts, t1s, ns, side, ends = [], [], [], [], []
    for k in range(2):
        gen = (a - sa * g["normals"][k]) / ca  # unit generator in plane k, from the apex
        pts.append(apex[None, :] + s[:, None] * gen[None, :])
        t1s.append(np.tile(-gen, (n, 1)))
        ns.append(np.tile(g["normals"][k], (n, 1)))
        side.append(np.full(n, k))
        ends += [apex + s1 * gen, apex + s2 * gen]
    ell = s2 - s1  # = L / cos(alpha_c)
    vol = math.pi * L / 3.0 * (R1 * R1 + R1 * R2 + R2 * R2)
    zbar = L * (R1 * R1 + 2 * R1 * R2 + 3 * R2 * R2) / (4 * (R1 * R1 + R1 * R2 + R2 * R2))
    centroid = c1 + zbar * a  # measured from the small end toward the large end
    z_min = min(c1[2] - R1 * cg, c2[2] - R2 * cg)
    return dict(
        placement=dict(
            kind="cone",
            apex=apex,
            axis=a,
            r1=R1,
            r2=R2,
            c1=c1,
            c2=c2,
            gamma=gamma,
            semi_angle=ac,
            length=L,
        ),
        points=np.vstack(pts),
        t1=np.vstack(t1s),
        n=np.vstack(ns),
        side=np.concatenate(side),
        weight=np.full(2 * n, ell / n),
        kind="line",
        extent=ell,
        line_ends=np.array(ends),
        volume=vol,
        centroid=centroid,
        x_extent=R2,
        z_min=z_min,
        notes=dict(gamma_deg=math.degrees(gamma), r2_mm=R2, contact_line_length_mm=ell),
    )


def fit_blame(gp: Any, g: dict, pl: dict, lo_ok: float, hi_ok: float, half_w: float):
    """R1 when the lines start above the platform tip, the length (or R1) when they reach
    below its root or run off its width."""
    sb, cb = math.sin(g["beta"]), math.cos(g["beta"])
    ca = math.cos(pl["semi_angle"])
    r1_lo = lo_ok * ca * sb / cb
    r2_hi = hi_ok * ca * sb / cb
    l_hi = (r2_hi - pl["r1"]) / math.tan(pl["semi_angle"])
    small = ("cone.r1_mm", pl["r1"], f"cone.r1_mm >= {r1_lo:.4g} mm")
    large = _cone_large("cone.length_mm", pl, l_hi, r2_hi)
    cg = math.cos(pl["gamma"])
    long_ = (
        "cone.length_mm",
        pl["length"],
        f"cone.length_mm <= {2 * half_w * ca * ca / cg:.4g} mm",
    )
    return small, large, long_


def hit_blame(gp: Any, g: dict, pl: dict, x_max: float):
    """The length (or R1), when the large end would touch the blades."""
    l_hi = (x_max - pl["r1"]) / math.tan(pl["semi_angle"])
    return _cone_large("cone.length_mm", pl, l_hi, x_max)


def draw(gmsh: Any, lay: Any, members: dict, point_tags: list) -> int:
    """The frustum, its seam turned down, the contact points embedded in its conical face."""
    from ..occ import embed_on_lateral_face

    occ = gmsh.model.occ
    pl = lay.damper
    c1, c2 = pl["c1"], pl["c2"]
    vol = occ.addCone(*map(float, c2), *map(float, c1 - c2), pl["r2"], pl["r1"])
    origin, axis = c2, -pl["axis"]
    return embed_on_lateral_face(gmsh, lay, vol, origin, axis, "Cone", members, point_tags)


SHAPE = DamperShape(
    name="cone",
    params=ConeParams,
    contact="line",
    seat=seat,
    fit_blame=fit_blame,
    hit_blame=hit_blame,
    draw=draw,
    style=("#0072B2", "-", "o"),  # Okabe-Ito blue (workbench/render/palette.py)
    study_options={
        "points-per-line": ("n_contact_points", int),
        "cone-angle": ("semi_angle_deg", float),
    },
    order=1,
    description="a frustum whose axis tilts in the y-z plane, one contact line on each platform",
)

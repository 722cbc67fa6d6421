r"""Where everything sits: the rig, the groove, the seated damper, the contact points.

Pure numpy, no gmsh: the builders in :mod:`.occ` only draw what this module
computes, and every "does it fit?" question is answered here, before gmsh
is called, with an InputError naming the parameter.

Lengths in millimetres inside this module (the CAD works in mm); the record
handed downstream converts to metres.

Rig and groove (a section at constant y, looking along +y)::

        z
        ^        blade 1                     blade 2
        |      |        |   tip gap    |        |
        |      |   +----+  <------->   +----+   |     platform top
        |      |   |     \   ridge   /     |    |
        |      |   |  P1  \    *    /  P2  |    |     P1, P2: inclined undersides,
        |      |   |       \       /       |    |     each at the angle beta from z
        |      |   |        \_____/        |    |
        |      |   |        (damper)       |    |
        |      +---+                       +----+
        |     outer inner               inner  outer
        +-------------------------------------------------> x
                              x = 0

The two platform planes meet (if extended) on the ridge line x = 0,
z = z_ridge, parallel to y. A plane k has the unit normal ``n[k]`` pointing
from the platform into the damper (down and toward the other blade)::

    n[0] = ( cos beta, 0, -sin beta)     (platform of blade 1, x < 0)
    n[1] = (-cos beta, 0, -sin beta)     (platform of blade 2, x > 0)

and the unit vector ``down[k]`` in the plane, away from the ridge
(``down[0] = (-sin beta, 0, -cos beta)``). A point of plane k is located by
its slope distance ``sigma = (p - ridge) . down[k]`` and its ``y``; the
inclined face spans ``s_tip <= sigma <= s_root``.

Seating (tangent to both planes, DESIGN.md section 4):

* cylinder: axis on x = 0 at ``z_ridge - R / sin beta``; contact generators
  at ``c - R n[k]``;
* cone: the apex lies on the ridge, the axis in the y-z plane tilted by
  ``gamma`` with ``sin gamma = sin alpha_c / sin beta``, large end at -y and
  lower; the generator in plane k is ``(a - sin alpha_c n[k]) / cos alpha_c``
  (``a`` the unit axis from the apex to the large end);
* wedge: the prism's contact faces are the strips ``s_a <= sigma <= s_b`` of
  the two planes, ``s_a = (top_width / 2) / sin beta``.

Contact points are cell-centred: a line of length l carries n points at the
midpoints of n equal segments (tributary length l / n each); a wedge face
carries rows at the middles of ``n_rows`` equal strips, rows alternating
``n_per_row`` and ``n_per_row - 1`` points (staggered), each point weighted
by its strip height times the length of its nearest-point (Voronoi) cell
along its row. The weights of one side sum to the line length (face area).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from .params import ConeParams, CylinderParams, GeometryParams, RigParams, WedgeParams

# Element-count guard: a size that would give more tetrahedra than this is
# refused before gmsh runs (gmsh needs about 1 kB per tetrahedron and minutes).
MAX_TETS = 4.0e6
# Tetrahedra per unit volume of a gmsh mesh of size h is about 8.5 / h^3
# (a regular tetrahedron of edge h has volume h^3 / (6 sqrt 2)).
TETS_PER_H3 = 8.5


@dataclass(frozen=True)
class Box:
    """An axis-aligned box, mm: the lower corner and the extents."""

    x0: float
    y0: float
    z0: float
    dx: float
    dy: float
    dz: float


@dataclass(frozen=True)
class Layout:
    """The seated assembly in millimetres (see the module docstring)."""

    params: GeometryParams
    beta: float  # rad
    z_ridge: float
    normals: np.ndarray  # (2, 3) n[k]
    down: np.ndarray  # (2, 3) down-slope unit vector in plane k
    s_tip: float  # slope distance ridge -> tip edge of the inclined face
    s_root: float  # slope distance ridge -> root edge (blade inner face)
    base: Box
    blades: tuple[Box, Box]
    platform_xz: tuple[np.ndarray, np.ndarray]  # (4, 2) polygons in the x-z plane
    platform_y: tuple[float, float]  # y range of the platforms
    outer_x: tuple[float, float]  # x of the outer faces of blade 1, 2
    excitation: np.ndarray  # (2, 3)
    response: np.ndarray  # (2, 3)
    damper: dict  # kind-specific placement (see _seat_*)
    points: np.ndarray  # (n_pairs, 3) contact points
    frames: np.ndarray  # (n_pairs, 3, 3) rows t1, t2, n
    side: np.ndarray  # (n_pairs,)
    weight: np.ndarray  # (n_pairs,) mm (lines) or mm^2 (faces)
    kind: str  # "line" | "face"
    extent: float  # length of one contact line (mm) or area of one face (mm^2)
    volume: float  # analytic damper volume, mm^3
    centroid: np.ndarray  # analytic damper centroid, mm
    contact_spacing: float  # smallest distance between two contact points, mm
    notes: dict = field(default_factory=dict)  # derived numbers worth reporting

    @property
    def n_pairs(self) -> int:
        return int(self.points.shape[0])

    def sigma(self, p: np.ndarray, k: int) -> np.ndarray:
        """Slope distance from the ridge of point(s) ``p`` in plane ``k``, mm."""
        ridge = np.array([0.0, 0.0, self.z_ridge])
        return (np.asarray(p, dtype=float) - ridge) @ self.down[k]

    def plane_distance(self, p: np.ndarray, k: int) -> np.ndarray:
        """Signed distance of point(s) ``p`` from plane ``k`` (positive on the damper side), mm."""
        ridge = np.array([0.0, 0.0, self.z_ridge])
        return (np.asarray(p, dtype=float) - ridge) @ self.normals[k]


def _cone_large(name: str, pl: dict, l_hi: float, r2_hi: float) -> tuple[str, float, str]:
    """The parameter to blame when the cone's large end does not fit: its length, or, when
    even the small radius is too large for any length, ``cone.r1_mm``."""
    if l_hi <= 0.0:
        return ("cone.r1_mm", pl["r1"], f"cone.r1_mm < {r2_hi:.4g} mm (the large radius "
                f"R2 = R1 + L tan(alpha_c) must stay <= {r2_hi:.4g} mm)")
    return (name, pl["length"],
            f"{name} <= {l_hi:.4g} mm (large radius R2 <= {r2_hi:.4g} mm)")


def _fit_error(param: str, value: float, allowed: str, why: str) -> InputError:
    return InputError(param, value, allowed, why)


def _rig(rig: RigParams) -> dict:
    """Rig boxes, platform polygons, groove planes; checks that the rig is consistent."""
    b, bl, pf, fit = rig.base, rig.blade, rig.platform, rig.fit
    beta = math.radians(pf.angle_deg)
    half_gap = bl.gap_mm / 2.0
    tip_gap = bl.gap_mm - 2.0 * pf.overhang_mm
    if tip_gap < fit.clearance_mm:
        hi = (bl.gap_mm - fit.clearance_mm) / 2.0
        raise _fit_error(
            "rig.platform.overhang_mm", pf.overhang_mm, f"rig.platform.overhang_mm <= {hi:.4g} mm",
            f"the two platforms would leave a tip gap of {tip_gap:.4g} mm; at least "
            f"rig.fit.clearance_mm = {fit.clearance_mm:g} mm is needed so they do not touch")
    if b.length_mm < bl.gap_mm + 2.0 * bl.thickness_mm:
        need = bl.gap_mm + 2.0 * bl.thickness_mm
        raise _fit_error("rig.base.length_mm", b.length_mm, f"rig.base.length_mm >= {need:.4g} mm",
                         "the base must carry both blades (gap + 2 x thickness)")
    if b.width_mm < bl.width_mm:
        raise _fit_error("rig.base.width_mm", b.width_mm,
                         f"rig.base.width_mm >= {bl.width_mm:g} mm",
                         "the base must carry the whole blade width")
    z_base = b.height_mm
    z_tip = z_base + bl.height_mm
    # steps below _SAME_MM are no steps (see _check_features): snap them shut
    z_top = z_tip - (pf.top_below_tip_mm if pf.top_below_tip_mm >= _SAME_MM else 0.0)
    drop = pf.overhang_mm / math.tan(beta)  # vertical drop of the inclined face
    depth = pf.tip_thickness_mm + drop
    z_root = z_top - depth
    if z_root < z_base + fit.clearance_mm or pf.top_below_tip_mm >= bl.height_mm:
        hi = bl.height_mm - depth - fit.clearance_mm
        raise _fit_error(
            "rig.platform.top_below_tip_mm", pf.top_below_tip_mm,
            f"0 <= rig.platform.top_below_tip_mm <= {max(hi, 0.0):.4g} mm",
            f"the platform ({depth:.4g} mm deep: tip {pf.tip_thickness_mm:g} mm + inclined face "
            f"{drop:.4g} mm) must sit on the blade, above the base")
    _check_features(rig)
    z_tb = z_top - pf.tip_thickness_mm  # z of the tip edge of the inclined face
    x_tip = half_gap - pf.overhang_mm
    z_ridge = z_tb + x_tip / math.tan(beta)
    sb, cb = math.sin(beta), math.cos(beta)
    normals = np.array([[cb, 0.0, -sb], [-cb, 0.0, -sb]])
    down = np.array([[-sb, 0.0, -cb], [sb, 0.0, -cb]])
    blades = (
        Box(-half_gap - bl.thickness_mm, -bl.width_mm / 2, z_base, bl.thickness_mm, bl.width_mm,
            bl.height_mm),
        Box(half_gap, -bl.width_mm / 2, z_base, bl.thickness_mm, bl.width_mm, bl.height_mm),
    )
    poly1 = np.array([[-half_gap, z_root], [-x_tip, z_tb], [-x_tip, z_top], [-half_gap, z_top]])
    poly2 = poly1 * np.array([-1.0, 1.0])
    outer = (-half_gap - bl.thickness_mm, half_gap + bl.thickness_mm)
    flush_len = bl.gap_mm + 2 * bl.thickness_mm
    base_len = flush_len if abs(b.length_mm - flush_len) < 2 * _SAME_MM else b.length_mm
    base_wid = bl.width_mm if abs(b.width_mm - bl.width_mm) < 2 * _SAME_MM else b.width_mm
    plat_wid = bl.width_mm if abs(pf.width_mm - bl.width_mm) < 2 * _SAME_MM else pf.width_mm
    pts = {}
    for name, rec in (("excitation", rig.excitation), ("response", rig.response)):
        m = fit.edge_margin_mm
        if not m <= rec.height_mm <= bl.height_mm - m:
            raise _fit_error(
                f"rig.{name}.height_mm", rec.height_mm,
                f"{m:g} <= rig.{name}.height_mm <= {bl.height_mm - m:.4g} mm",
                "the point must lie on the blade's outer face, rig.fit.edge_margin_mm "
                "from its edges")
        if abs(rec.y_mm) > bl.width_mm / 2 - m:
            lim = bl.width_mm / 2 - m
            raise _fit_error(f"rig.{name}.y_mm", rec.y_mm,
                             f"{-lim:.4g} <= rig.{name}.y_mm <= {lim:.4g} mm",
                             "the point must lie on the blade's outer face")
        pts[name] = np.array([[outer[0], rec.y_mm, z_base + rec.height_mm],
                              [outer[1], rec.y_mm, z_base + rec.height_mm]])
    if np.linalg.norm(pts["excitation"][0] - pts["response"][0]) < fit.edge_margin_mm:
        raise _fit_error("rig.response.height_mm", rig.response.height_mm,
                         "a point at least rig.fit.edge_margin_mm from the excitation point",
                         "the excitation and response points coincide")
    return dict(
        beta=beta, z_ridge=z_ridge, normals=normals, down=down,
        s_tip=x_tip / sb, s_root=half_gap / sb,
        base=Box(-base_len / 2, -base_wid / 2, 0.0, base_len, base_wid, b.height_mm),
        blades=blades, platform_xz=(poly1, poly2),
        platform_y=(-plat_wid / 2, plat_wid / 2), outer_x=outer,
        excitation=pts["excitation"], response=pts["response"],
        z_root=z_root, z_base=z_base, half_gap=half_gap, min_feature=fit.min_feature_mm,
    )


# Two faces closer than this are the same face to the CAD kernel (its
# tolerance is 1e-7 mm): a step below it is "no step".
_SAME_MM = 1e-6


def _step(param: str, value: float, step: float, f: float, what: str) -> None:
    """A step between faces is absent (below _SAME_MM) or at least ``f``; else InputError."""
    if _SAME_MM <= abs(step) < f:
        raise _fit_error(
            param, value, f"a value that leaves no step or a step of at least "
            f"rig.fit.min_feature_mm = {f:g} mm", f"{what} would be {abs(step):.3g} mm")


def _check_features(rig: RigParams) -> None:
    """Refuse slivers: steps between rig faces that are neither absent nor >= min_feature_mm."""
    f = rig.fit.min_feature_mm
    b, bl, pf = rig.base, rig.blade, rig.platform
    if pf.tip_thickness_mm < f:
        raise _fit_error("rig.platform.tip_thickness_mm", pf.tip_thickness_mm,
                         f"rig.platform.tip_thickness_mm >= rig.fit.min_feature_mm = {f:g} mm",
                         "the platform tip face would be a sliver")
    _step("rig.platform.top_below_tip_mm", pf.top_below_tip_mm, pf.top_below_tip_mm, f,
          "the step from the platform top to the blade tip")
    _step("rig.platform.width_mm", pf.width_mm, (pf.width_mm - bl.width_mm) / 2, f,
          "the axial step between the platform and the blade on each side")
    _step("rig.base.length_mm", b.length_mm, (b.length_mm - bl.gap_mm) / 2 - bl.thickness_mm, f,
          "the ledge of the base beside each blade")
    _step("rig.base.width_mm", b.width_mm, (b.width_mm - bl.width_mm) / 2, f,
          "the ledge of the base in front of and behind the blades")
    tip_gap = bl.gap_mm - 2 * pf.overhang_mm
    if tip_gap < f:
        raise _fit_error("rig.platform.overhang_mm", pf.overhang_mm,
                         f"rig.platform.overhang_mm <= {(bl.gap_mm - f) / 2:.4g} mm",
                         f"the gap between the platform tips would be {tip_gap:.3g} mm")


def _frames(t1: np.ndarray, n: np.ndarray) -> np.ndarray:
    """Rows (t1, t2 = n x t1, n) for each pair."""
    t2 = np.cross(n, t1)
    return np.stack([t1, t2, n], axis=1)


def _voronoi_1d(x: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Length of each sorted point's nearest-point cell within [lo, hi]."""
    mids = 0.5 * (x[1:] + x[:-1])
    edges = np.concatenate([[lo], mids, [hi]])
    return np.diff(edges)


def _seat_cylinder(p: CylinderParams, g: dict) -> dict:
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
    ends = [(c - R * g["normals"][k]) + s * np.array([0.0, L / 2, 0.0])
            for k in range(2) for s in (-1.0, 1.0)]
    return dict(
        placement=dict(kind="cylinder", center=c, axis=np.array([0.0, 1.0, 0.0]), radius=R,
                       length=L, y0=-L / 2),
        points=np.vstack(pts), t1=np.vstack(t1s), n=np.vstack(ns), side=np.concatenate(side),
        weight=np.full(2 * n, L / n), kind="line", extent=L, line_ends=np.array(ends),
        volume=math.pi * R * R * L, centroid=c.copy(),
        x_extent=R, z_min=zc - R,
        notes=dict(contact_line_length_mm=L),
    )


def _seat_cone(p: ConeParams, g: dict, rig: RigParams) -> dict:
    beta = g["beta"]
    ac = math.radians(p.semi_angle_deg)
    if ac >= beta:
        raise InputError(
            "cone.semi_angle_deg", p.semi_angle_deg,
            f"0 < cone.semi_angle_deg < rig.platform.angle_deg = {rig.platform.angle_deg:g} deg",
            "a cone touches both platform planes along generators only if its axis tilts by "
            "gamma with sin(gamma) = sin(alpha_c) / sin(beta); for alpha_c >= beta that has no "
            "solution (at alpha_c = beta the cone would stand vertical)")
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
        placement=dict(kind="cone", apex=apex, axis=a, r1=R1, r2=R2, c1=c1, c2=c2,
                       gamma=gamma, semi_angle=ac, length=L),
        points=np.vstack(pts), t1=np.vstack(t1s), n=np.vstack(ns), side=np.concatenate(side),
        weight=np.full(2 * n, ell / n), kind="line", extent=ell, line_ends=np.array(ends),
        volume=vol, centroid=centroid, x_extent=R2, z_min=z_min,
        notes=dict(gamma_deg=math.degrees(gamma), r2_mm=R2, contact_line_length_mm=ell),
    )


def _seat_wedge(p: WedgeParams, g: dict) -> dict:
    beta = g["beta"]
    sb = math.sin(beta)
    L, ny, ns_rows = p.length_mm, p.n_contact_per_row, p.n_contact_rows
    s_a = (p.top_width_mm / 2) / sb
    s_b = s_a + p.face_width_mm
    ridge = np.array([0.0, 0.0, g["z_ridge"]])
    up1 = ridge + s_a * g["down"][0]
    lo1 = ridge + s_b * g["down"][0]
    skirt = p.skirt_height_mm if p.skirt_height_mm >= _SAME_MM else 0.0
    z_bot = lo1[2] - skirt
    # section polygon in the x-z plane, counter-clockwise seen from +y... order is irrelevant
    poly = np.array([
        [up1[0], up1[2]], [lo1[0], lo1[2]], [lo1[0], z_bot],
        [-lo1[0], z_bot], [-lo1[0], lo1[2]], [-up1[0], up1[2]],
    ])
    if skirt == 0.0:
        poly = np.delete(poly, [2, 3], axis=0)
    f = g["min_feature"]
    _step("wedge.skirt_height_mm", p.skirt_height_mm, p.skirt_height_mm, f,
          "the height of the wedge's vertical sides")
    if p.face_width_mm < f:
        raise _fit_error("wedge.face_width_mm", p.face_width_mm,
                         f"wedge.face_width_mm >= rig.fit.min_feature_mm = {f:g} mm",
                         "the contact faces would be slivers")
    h = p.face_width_mm / ns_rows
    rows_s = s_b - (np.arange(ns_rows) + 0.5) * h  # row 0 lowest, up the slope
    full_y = -L / 2 + (np.arange(ny) + 0.5) * L / ny
    short_y = -L / 2 + (np.arange(1, ny)) * L / ny
    pts, t1s, ns, side, weight = [], [], [], [], []
    for k in range(2):
        for j, sj in enumerate(rows_s):
            ys = full_y if j % 2 == 0 else short_y
            w = _voronoi_1d(ys, -L / 2, L / 2) * h
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
        points=np.vstack(pts), t1=np.vstack(t1s), n=np.vstack(ns), side=np.concatenate(side),
        weight=np.concatenate(weight), kind="face", extent=p.face_width_mm * L,
        line_ends=np.array(ends),
        volume=abs(area) * L, centroid=np.array([cx, 0.0, cz]),
        x_extent=float(np.abs(poly[:, 0]).max()), z_min=float(poly[:, 1].min()),
        notes=dict(contact_face_area_mm2=p.face_width_mm * L,
                   points_per_face=int(sum(ny if j % 2 == 0 else ny - 1 for j in range(ns_rows)))),
    )


def _check_fit(gp: GeometryParams, g: dict, seat: dict) -> None:
    """Refuse a damper whose contacts run off the platform faces or that hits the rig."""
    rig, fit, d = gp.rig, gp.rig.fit, gp.damper
    m, clr = fit.edge_margin_mm, fit.clearance_mm
    sb, cb = math.sin(g["beta"]), math.cos(g["beta"])
    ridge = np.array([0.0, 0.0, g["z_ridge"]])
    ends = seat["line_ends"]
    sig = np.array([(e - ridge) @ g["down"][0 if e[0] < 0 else 1] for e in ends])
    lo_ok, hi_ok = g["s_tip"] + m, g["s_root"] - m
    half_w = rig.platform.width_mm / 2 - m
    where = ("the contact lines" if seat["kind"] == "line" else "the contact faces")
    pl = seat["placement"]
    if seat["kind"] == "line" and d == "cylinder":
        r_lo, r_hi = lo_ok * sb / cb, hi_ok * sb / cb
        rng = f"{r_lo:.4g} <= cylinder.radius_mm <= {r_hi:.4g} mm"
        small, large = ("cylinder.radius_mm", pl["radius"], rng), ("cylinder.radius_mm",
                                                                  pl["radius"], rng)
        long_ = ("cylinder.length_mm", pl["length"], f"cylinder.length_mm <= {2 * half_w:.4g} mm")
    elif d == "cone":
        ca = math.cos(pl["semi_angle"])
        r1_lo = lo_ok * ca * sb / cb
        r2_hi = hi_ok * ca * sb / cb
        l_hi = (r2_hi - pl["r1"]) / math.tan(pl["semi_angle"])
        small = ("cone.r1_mm", pl["r1"], f"cone.r1_mm >= {r1_lo:.4g} mm")
        large = _cone_large("cone.length_mm", pl, l_hi, r2_hi)
        cg = math.cos(pl["gamma"])
        long_ = ("cone.length_mm", pl["length"],
                 f"cone.length_mm <= {2 * half_w * ca * ca / cg:.4g} mm")
    else:
        small = ("wedge.top_width_mm", gp.shape.top_width_mm,
                 f"wedge.top_width_mm >= {2 * lo_ok * sb:.4g} mm")
        large = ("wedge.face_width_mm", gp.shape.face_width_mm,
                 f"wedge.face_width_mm <= {hi_ok - pl['s_a']:.4g} mm")
        long_ = ("wedge.length_mm", pl["length"], f"wedge.length_mm <= {2 * half_w:.4g} mm")
    face = (f"the inclined platform faces span {g['s_tip']:.4g} to {g['s_root']:.4g} mm down "
            f"the slope from the ridge; rig.fit.edge_margin_mm = {m:g} mm")
    if sig.min() < lo_ok - 1e-9:
        raise _fit_error(*small, f"{where} would start {sig.min():.4g} mm down the slope, above "
                         f"the platform tip edge: {face}")
    if sig.max() > hi_ok + 1e-9:
        raise _fit_error(*large, f"{where} would reach {sig.max():.4g} mm down the slope, below "
                         f"the platform root: {face}")
    if np.abs(ends[:, 1]).max() > half_w + 1e-9:
        raise _fit_error(*long_, f"{where} would reach y = +-{np.abs(ends[:, 1]).max():.4g} mm, "
                         f"beyond the platform width rig.platform.width_mm = "
                         f"{rig.platform.width_mm:g} mm less the edge margin")
    x_max = g["half_gap"] - clr
    if seat["x_extent"] > x_max + 1e-9:
        if d == "cylinder":
            hit = ("cylinder.radius_mm", pl["radius"], f"cylinder.radius_mm <= {x_max:.4g} mm")
        elif d == "cone":
            l_hi = (x_max - pl["r1"]) / math.tan(pl["semi_angle"])
            hit = _cone_large("cone.length_mm", pl, l_hi, x_max)
        else:
            hit = ("wedge.face_width_mm", gp.shape.face_width_mm,
                   f"wedge.face_width_mm <= {max(x_max / sb - pl['s_a'], 0.0):.4g} mm")
        raise _fit_error(
            *hit, f"the damper would reach x = +-{seat['x_extent']:.4g} mm and hit the blades "
            f"(inner faces at +-{g['half_gap']:.4g} mm, clearance rig.fit.clearance_mm = "
            f"{clr:g} mm)")
    if seat["z_min"] < g["z_base"] + clr - 1e-9:
        raise _fit_error(
            "rig.blade.height_mm", rig.blade.height_mm,
            "a blade tall enough to keep the damper above the base",
            f"the damper would reach down to z = {seat['z_min']:.4g} mm, below the base top "
            f"z = {g['z_base']:.4g} mm plus the clearance")


def _check_mesh(gp: GeometryParams, g: dict, seat: dict, spacing: float) -> None:
    """Refuse sizes that would produce an unreasonable number of elements."""
    rig, ms = gp.rig, gp.rig.mesh
    vol_rig = rig.base.length_mm * rig.base.width_mm * rig.base.height_mm + 2 * (
        rig.blade.thickness_mm * rig.blade.width_mm * rig.blade.height_mm)
    for name, h, vol in (("rig.mesh.size_mm", ms.size_mm, vol_rig),
                         ("rig.mesh.damper_size_mm", min(ms.damper_size_mm, ms.size_mm),
                          seat["volume"])):
        n_est = TETS_PER_H3 * vol / h**3
        if n_est > MAX_TETS:
            h_min = (TETS_PER_H3 * vol / MAX_TETS) ** (1 / 3)
            raise InputError(
                name, h, f"{name} >= {h_min:.3g} mm",
                f"about {n_est:.3g} tetrahedra; the limit is {MAX_TETS:.3g}")
    h_c = min(ms.contact_size_mm, spacing)
    n_ref = seat["points"].shape[0] * refinement_tets(h_c, ms.size_mm, ms.refine_distance_mm)
    if n_ref > MAX_TETS:
        raise InputError(
            "rig.mesh.contact_size_mm", ms.contact_size_mm,
            "a larger contact size, fewer contact points or a shorter rig.mesh.refine_distance_mm",
            f"about {n_ref:.3g} tetrahedra around the contact points "
            f"({seat['points'].shape[0]} points, {spacing:.3g} mm apart); the limit is "
            f"{MAX_TETS:.3g}")


def refinement_tets(h_c: float, h: float, dist: float) -> float:
    """Upper estimate of the tetrahedra around one contact point, mm sizes.

    The size is ``h_c`` within ``h_c`` of the point and grows linearly to
    ``h`` at ``dist`` (the gmsh Threshold field used by the builders); the
    count integrates ``TETS_PER_H3 / size^3`` over the ball (overlaps
    between neighbouring points are not removed, hence an upper estimate).
    """
    h_c = min(h_c, h)
    r = np.linspace(h_c, max(dist, h_c * (1 + 1e-9)), 400)
    size = h_c + (h - h_c) * (r - h_c) / max(dist - h_c, 1e-12)
    f = 4 * math.pi * r**2 / size**3
    shell = float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(r)))
    return TETS_PER_H3 * (4 / 3 * math.pi + shell)


def make_layout(gp: GeometryParams) -> Layout:
    """Seat the chosen damper in the groove of the rig; raise InputError if it does not fit."""
    g = _rig(gp.rig)
    if gp.damper == "cone":
        seat = _seat_cone(gp.shape, g, gp.rig)
    elif gp.damper == "cylinder":
        seat = _seat_cylinder(gp.shape, g)
    else:
        seat = _seat_wedge(gp.shape, g)
    _check_fit(gp, g, seat)
    pts = seat["points"]
    from scipy.spatial import cKDTree

    dd, _ = cKDTree(pts).query(pts, k=2)
    spacing = float(dd[:, 1].min())
    _check_mesh(gp, g, seat, spacing)
    notes = dict(seat["notes"])
    notes.update(z_ridge_mm=g["z_ridge"],
                 tip_gap_mm=2 * (g["half_gap"] - gp.rig.platform.overhang_mm),
                 contact_spacing_mm=spacing)
    return Layout(
        params=gp, beta=g["beta"], z_ridge=g["z_ridge"], normals=g["normals"], down=g["down"],
        s_tip=g["s_tip"], s_root=g["s_root"], base=g["base"], blades=g["blades"],
        platform_xz=g["platform_xz"], platform_y=g["platform_y"], outer_x=g["outer_x"],
        excitation=g["excitation"], response=g["response"], damper=seat["placement"],
        points=pts, frames=_frames(seat["t1"], seat["n"]), side=seat["side"],
        weight=seat["weight"], kind=seat["kind"], extent=seat["extent"],
        volume=seat["volume"], centroid=seat["centroid"], contact_spacing=spacing, notes=notes,
    )

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

Seating (tangent to both planes, DESIGN.md section 4; each shape's own
``seat`` in :mod:`.shapes`, e.g. :mod:`.shapes.cone`):

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
from .params import GeometryParams, RigParams
from .seat_tools import SAME_MM as _SAME_MM
from .seat_tools import check_step as _step
from .seat_tools import fit_error as _fit_error
from .shapes import get as get_shape

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


def _rig(rig: RigParams) -> dict:
    """Rig boxes, platform polygons, groove planes; checks that the rig is consistent."""
    b, bl, pf, fit = rig.base, rig.blade, rig.platform, rig.fit
    beta = math.radians(pf.angle_deg)
    half_gap = bl.gap_mm / 2.0
    tip_gap = bl.gap_mm - 2.0 * pf.overhang_mm
    if tip_gap < fit.clearance_mm:
        hi = (bl.gap_mm - fit.clearance_mm) / 2.0
        raise _fit_error(
            "rig.platform.overhang_mm",
            pf.overhang_mm,
            f"rig.platform.overhang_mm <= {hi:.4g} mm",
            f"the two platforms would leave a tip gap of {tip_gap:.4g} mm; at least "
            f"rig.fit.clearance_mm = {fit.clearance_mm:g} mm is needed so they do not touch",
        )
    if b.length_mm < bl.gap_mm + 2.0 * bl.thickness_mm:
        need = bl.gap_mm + 2.0 * bl.thickness_mm
        raise _fit_error(
            "rig.base.length_mm",
            b.length_mm,
            f"rig.base.length_mm >= {need:.4g} mm",
            "the base must carry both blades (gap + 2 x thickness)",
        )
    if b.width_mm < bl.width_mm:
        raise _fit_error(
            "rig.base.width_mm",
            b.width_mm,
            f"rig.base.width_mm >= {bl.width_mm:g} mm",
            "the base must carry the whole blade width",
        )
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
            "rig.platform.top_below_tip_mm",
            pf.top_below_tip_mm,
            f"0 <= rig.platform.top_below_tip_mm <= {max(hi, 0.0):.4g} mm",
            f"the platform ({depth:.4g} mm deep: tip {pf.tip_thickness_mm:g} mm + inclined face "
            f"{drop:.4g} mm) must sit on the blade, above the base",
        )
    _check_features(rig)
    z_tb = z_top - pf.tip_thickness_mm  # z of the tip edge of the inclined face
    x_tip = half_gap - pf.overhang_mm
    z_ridge = z_tb + x_tip / math.tan(beta)
    sb, cb = math.sin(beta), math.cos(beta)
    normals = np.array([[cb, 0.0, -sb], [-cb, 0.0, -sb]])
    down = np.array([[-sb, 0.0, -cb], [sb, 0.0, -cb]])
    blades = (
        Box(
            -half_gap - bl.thickness_mm,
            -bl.width_mm / 2,
            z_base,
            bl.thickness_mm,
            bl.width_mm,
            bl.height_mm,
        ),
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
                f"rig.{name}.height_mm",
                rec.height_mm,
                f"{m:g} <= rig.{name}.height_mm <= {bl.height_mm - m:.4g} mm",
                "the point must lie on the blade's outer face, rig.fit.edge_margin_mm "
                "from its edges",
            )
        if abs(rec.y_mm) > bl.width_mm / 2 - m:
            lim = bl.width_mm / 2 - m
            raise _fit_error(
                f"rig.{name}.y_mm",
                rec.y_mm,
                f"{-lim:.4g} <= rig.{name}.y_mm <= {lim:.4g} mm",
                "the point must lie on the blade's outer face",
            )
        pts[name] = np.array(
            [
                [outer[0], rec.y_mm, z_base + rec.height_mm],
                [outer[1], rec.y_mm, z_base + rec.height_mm],
            ]
        )
    if np.linalg.norm(pts["excitation"][0] - pts["response"][0]) < fit.edge_margin_mm:
        raise _fit_error(
            "rig.response.height_mm",
            rig.response.height_mm,
            "a point at least rig.fit.edge_margin_mm from the excitation point",
            "the excitation and response points coincide",
        )
    return dict(
        beta=beta,
        z_ridge=z_ridge,
        normals=normals,
        down=down,
        s_tip=x_tip / sb,
        s_root=half_gap / sb,
        base=Box(-base_len / 2, -base_wid / 2, 0.0, base_len, base_wid, b.height_mm),
        blades=blades,
        platform_xz=(poly1, poly2),
        platform_y=(-plat_wid / 2, plat_wid / 2),
        outer_x=outer,
        excitation=pts["excitation"],
        response=pts["response"],
        z_root=z_root,
        z_base=z_base,
        half_gap=half_gap,
        min_feature=fit.min_feature_mm,
    )


def _check_features(rig: RigParams) -> None:
    """Refuse slivers: steps between rig faces that are neither absent nor >= min_feature_mm."""
    f = rig.fit.min_feature_mm
    b, bl, pf = rig.base, rig.blade, rig.platform
    if pf.tip_thickness_mm < f:
        raise _fit_error(
            "rig.platform.tip_thickness_mm",
            pf.tip_thickness_mm,
            f"rig.platform.tip_thickness_mm >= rig.fit.min_feature_mm = {f:g} mm",
            "the platform tip face would be a sliver",
        )
    _step(
        "rig.platform.top_below_tip_mm",
        pf.top_below_tip_mm,
        pf.top_below_tip_mm,
        f,
        "the step from the platform top to the blade tip",
    )
    _step(
        "rig.platform.width_mm",
        pf.width_mm,
        (pf.width_mm - bl.width_mm) / 2,
        f,
        "the axial step between the platform and the blade on each side",
    )
    _step(
        "rig.base.length_mm",
        b.length_mm,
        (b.length_mm - bl.gap_mm) / 2 - bl.thickness_mm,
        f,
        "the ledge of the base beside each blade",
    )
    _step(
        "rig.base.width_mm",
        b.width_mm,
        (b.width_mm - bl.width_mm) / 2,
        f,
        "the ledge of the base in front of and behind the blades",
    )
    tip_gap = bl.gap_mm - 2 * pf.overhang_mm
    if tip_gap < f:
        raise _fit_error(
            "rig.platform.overhang_mm",
            pf.overhang_mm,
            f"rig.platform.overhang_mm <= {(bl.gap_mm - f) / 2:.4g} mm",
            f"the gap between the platform tips would be {tip_gap:.3g} mm",
        )


def _frames(t1: np.ndarray, n: np.ndarray) -> np.ndarray:
    """Rows (t1, t2 = n x t1, n) for each pair."""
    t2 = np.cross(n, t1)
    return np.stack([t1, t2, n], axis=1)


def _check_fit(gp: GeometryParams, g: dict, seat: dict) -> None:
    """Refuse a damper whose contacts run off the platform faces or that hits the rig."""
    rig, fit = gp.rig, gp.rig.fit
    shape = get_shape(gp.damper)
    m, clr = fit.edge_margin_mm, fit.clearance_mm
    ridge = np.array([0.0, 0.0, g["z_ridge"]])
    ends = seat["line_ends"]
    sig = np.array([(e - ridge) @ g["down"][0 if e[0] < 0 else 1] for e in ends])
    lo_ok, hi_ok = g["s_tip"] + m, g["s_root"] - m
    half_w = rig.platform.width_mm / 2 - m
    where = "the contact lines" if seat["kind"] == "line" else "the contact faces"
    pl = seat["placement"]
    small, large, long_ = shape.fit_blame(gp, g, pl, lo_ok, hi_ok, half_w)
    face = (
        f"the inclined platform faces span {g['s_tip']:.4g} to {g['s_root']:.4g} mm down "
        f"the slope from the ridge; rig.fit.edge_margin_mm = {m:g} mm"
    )
    if sig.min() < lo_ok - 1e-9:
        raise _fit_error(
            *small,
            f"{where} would start {sig.min():.4g} mm down the slope, above "
            f"the platform tip edge: {face}",
        )
    if sig.max() > hi_ok + 1e-9:
        raise _fit_error(
            *large,
            f"{where} would reach {sig.max():.4g} mm down the slope, below "
            f"the platform root: {face}",
        )
    if np.abs(ends[:, 1]).max() > half_w + 1e-9:
        raise _fit_error(
            *long_,
            f"{where} would reach y = +-{np.abs(ends[:, 1]).max():.4g} mm, "
            f"beyond the platform width rig.platform.width_mm = "
            f"{rig.platform.width_mm:g} mm less the edge margin",
        )
    x_max = g["half_gap"] - clr
    if seat["x_extent"] > x_max + 1e-9:
        raise _fit_error(
            *shape.hit_blame(gp, g, pl, x_max),
            f"the damper would reach x = +-{seat['x_extent']:.4g} mm and hit the blades "
            f"(inner faces at +-{g['half_gap']:.4g} mm, clearance rig.fit.clearance_mm = "
            f"{clr:g} mm)",
        )
    if seat["z_min"] < g["z_base"] + clr - 1e-9:
        raise _fit_error(
            "rig.blade.height_mm",
            rig.blade.height_mm,
            "a blade tall enough to keep the damper above the base",
            f"the damper would reach down to z = {seat['z_min']:.4g} mm, below the base top "
            f"z = {g['z_base']:.4g} mm plus the clearance",
        )


def _check_mesh(gp: GeometryParams, g: dict, seat: dict, spacing: float) -> None:
    """Refuse sizes that would produce an unreasonable number of elements."""
    rig, ms = gp.rig, gp.rig.mesh
    vol_rig = rig.base.length_mm * rig.base.width_mm * rig.base.height_mm + 2 * (
        rig.blade.thickness_mm * rig.blade.width_mm * rig.blade.height_mm
    )
    for name, h, vol in (
        ("rig.mesh.size_mm", ms.size_mm, vol_rig),
        ("rig.mesh.damper_size_mm", min(ms.damper_size_mm, ms.size_mm), seat["volume"]),
    ):
        n_est = TETS_PER_H3 * vol / h**3
        if n_est > MAX_TETS:
            h_min = (TETS_PER_H3 * vol / MAX_TETS) ** (1 / 3)
            raise InputError(
                name,
                h,
                f"{name} >= {h_min:.3g} mm",
                f"about {n_est:.3g} tetrahedra; the limit is {MAX_TETS:.3g}",
            )
    h_c = min(ms.contact_size_mm, spacing)
    n_ref = seat["points"].shape[0] * refinement_tets(h_c, ms.size_mm, ms.refine_distance_mm)
    if n_ref > MAX_TETS:
        raise InputError(
            "rig.mesh.contact_size_mm",
            ms.contact_size_mm,
            "a larger contact size, fewer contact points or a shorter rig.mesh.refine_distance_mm",
            f"about {n_ref:.3g} tetrahedra around the contact points "
            f"({seat['points'].shape[0]} points, {spacing:.3g} mm apart); the limit is "
            f"{MAX_TETS:.3g}",
        )


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
    seat = get_shape(gp.damper).seat(gp.shape, g, gp.rig)
    _check_fit(gp, g, seat)
    pts = seat["points"]
    from scipy.spatial import cKDTree

    dd, _ = cKDTree(pts).query(pts, k=2)
    spacing = float(dd[:, 1].min())
    _check_mesh(gp, g, seat, spacing)
    notes = dict(seat["notes"])
    notes.update(
        z_ridge_mm=g["z_ridge"],
        tip_gap_mm=2 * (g["half_gap"] - gp.rig.platform.overhang_mm),
        contact_spacing_mm=spacing,
        damper_x_extent_mm=float(seat["x_extent"]),
        damper_z_min_mm=float(seat["z_min"]),
    )
    return Layout(
        params=gp,
        beta=g["beta"],
        z_ridge=g["z_ridge"],
        normals=g["normals"],
        down=g["down"],
        s_tip=g["s_tip"],
        s_root=g["s_root"],
        base=g["base"],
        blades=g["blades"],
        platform_xz=g["platform_xz"],
        platform_y=g["platform_y"],
        outer_x=g["outer_x"],
        excitation=g["excitation"],
        response=g["response"],
        damper=seat["placement"],
        points=pts,
        frames=_frames(seat["t1"], seat["n"]),
        side=seat["side"],
        weight=seat["weight"],
        kind=seat["kind"],
        extent=seat["extent"],
        volume=seat["volume"],
        centroid=seat["centroid"],
        contact_spacing=spacing,
        notes=notes,
    )

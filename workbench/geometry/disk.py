r"""A bladed-disk sector: one blade of the rig's section on a disk of N blades.

Pure numpy, no gmsh (the builder is :mod:`.disk_occ`). Every "does it fit?"
question is answered here, before gmsh runs, with an InputError naming the
parameter, its value and the allowed range.

Axes and angles (millimetres here, metres in the record)::

    y            the disk axis (the rig's axial direction, along the damper)
    z            radial at the sector's centre (the blade's span)
    x            tangential at the sector's centre
    theta        the angle about y from +z toward +x; a point at radius r and
                 angle theta is (r sin theta, y, r cos theta)

The sector spans ``-alpha/2 <= theta <= alpha/2``, ``alpha = 2 pi / N``; the
blade is centred on ``theta = 0``. ``rotation(a)`` turns a point by ``a``
about +y (``theta -> theta + a``). Sector ``j`` of the disk is sector 0
turned by ``j alpha``; its right neighbour (``j + 1``) lies at larger theta.

How the rig's groove becomes the disk's groove. The rig's layout
(:func:`workbench.geometry.layout.make_layout`, rig and damper parameters
unchanged) is taken as the groove between this sector's blade (the rig's
blade 1, x < 0) and the next sector's (blade 2): the rig's mid-plane x = 0
is put on the sector boundary ``theta = alpha/2`` by the rigid map::

    G(p) = rotation(alpha/2) (p + (0, 0, c))           (rig frame -> disk)

with ``c`` chosen so that the root edge of the rig's inclined platform face
lies on the disk blade's side face ``x = t/2``. The two inclined faces, the
ridge, the seated damper, its contact points and frames are the rig's,
moved by ``G``: the damper fits the disk exactly as it fits the rig. The
radial blades are the rig's blades turned by ``-alpha/2`` about that root
edge, so the pitch at the platform is the rig's (blade gap + thickness):
the disk's radius follows from N, ``R_root = ... ~ pitch / (2 sin(alpha/2))``.
The platform halves are the rig's platform section, extended into the
blade up to its centre plane; this sector's left half is the mirror image
(x -> -x) of its right half. The hub is an annular sector of the rig base's
height (radially) and width (axially) below the blade root.

Contact pairs (``ContactSet``-like, disk frame): side 0 is this sector's
right platform half; side 1 is the next sector's left half. The platform
node of a side-1 pair belongs to the neighbour; its image in this sector,
``rotation(-alpha) p``, is a node of this sector's left half
(``image_points``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..config import load_record, param, read_toml
from ..errors import InputError, check_int
from .layout import Layout, make_layout
from .params import DEFAULT_DIR, GeometryParams

DEFAULT_FILE = DEFAULT_DIR / "disk.toml"
MAX_BLADES = 400  # beyond this the sector's width is a few mesh elements of any rig section


@dataclass(frozen=True)
class DiskParams:
    """The disk's own inputs (table ``[disk]``); the section comes from the rig tables."""

    n_blades: int = param(36, "number of blades (sectors) on the disk", lo=2, hi=MAX_BLADES)
    bore: str = param(
        "clamped", "the hub's inner (bore) face: clamped or free", choices=("clamped", "free")
    )


def load_disk_params(path: str | None = None, **overrides: object) -> DiskParams:
    """``geometry/disk.toml`` < ``path`` (its ``[disk]`` table) < ``overrides`` (None ignored)."""
    data: dict = {}
    for src in (DEFAULT_FILE if DEFAULT_FILE.is_file() else None, path):
        if src is not None:
            raw = read_toml(src)
            extra = sorted(set(raw) - {"disk"})
            if extra:
                raise InputError(f"[{extra[0]}] in {src}", "a table", "the table [disk] only")
            data.update(raw.get("disk", {}))
    data.update({k: v for k, v in overrides.items() if v is not None})
    if "n_blades" in data:
        check_int("disk.n_blades", data["n_blades"], 2, MAX_BLADES)
    return load_record(DiskParams, data, "disk.")


def rotation(angle: float) -> np.ndarray:
    """(3, 3) rotation by ``angle`` (rad) about +y: theta -> theta + angle."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


@dataclass(frozen=True)
class DiskLayout:
    """The sector in millimetres (see the module docstring)."""

    disk: DiskParams
    rig: Layout  # the rig's layout: the groove and damper in the rig frame
    alpha: float  # sector angle, rad
    shift: float  # c of G, mm
    r_in: float  # bore radius, mm
    r_root: float  # blade root (rim) radius, mm
    r_tip: float  # blade tip radius, mm
    blade_z0: float  # bottom of the blade box (inside the hub), mm
    width: float  # hub's axial width, mm
    platform_right: np.ndarray  # (5, 2) x-z polygon of the right platform half, disk frame
    points: np.ndarray  # (n_pairs, 3) contact points (damper nodes), disk frame
    frames: np.ndarray  # (n_pairs, 3, 3) rows t1, t2, n, disk frame
    side: np.ndarray  # (n_pairs,) 0: this sector's right half, 1: the next sector's left half
    image_points: np.ndarray  # (n_pairs, 3) platform node in this sector (side 1 rotated back)
    excitation: np.ndarray  # (3,) on the blade's left face
    response: np.ndarray  # (3,)

    @property
    def n_blades(self) -> int:
        return self.disk.n_blades

    @property
    def rot(self) -> np.ndarray:
        """rotation(alpha): sector j -> sector j + 1."""
        return rotation(self.alpha)

    def to_disk(self, p: np.ndarray) -> np.ndarray:
        """G: rig-frame point(s) (mm) -> disk frame (mm)."""
        p = np.atleast_2d(np.asarray(p, dtype=float)) + np.array([0.0, 0.0, self.shift])
        return p @ rotation(self.alpha / 2).T

    @property
    def frame_rotation(self) -> np.ndarray:
        """The rotation part of G (rig -> disk)."""
        return rotation(self.alpha / 2)


def _geometry(lay: Layout, n: int) -> dict:
    """Radii, shift and polygons for ``n`` blades (no checks)."""
    rig = lay.params.rig
    t = rig.blade.thickness_mm
    a = 2 * math.pi / n
    ha = a / 2
    half_gap = rig.blade.gap_mm / 2
    poly = lay.platform_xz[0]  # root (-half_gap, z_root), tip bottom, tip top, (-half_gap, z_top)
    z_root, z_top = float(poly[0, 1]), float(poly[3, 1])
    # the root edge (-half_gap, z_root) on the blade face x_disk = t/2
    shift = (t / 2 + half_gap * math.cos(ha)) / math.sin(ha) - z_root
    root_r = half_gap * math.sin(ha) + (z_root + shift) * math.cos(ha)  # z_disk of the root edge
    r_root = root_r - (z_root - rig.base.height_mm)
    r_in = r_root - rig.base.height_mm
    blade_z0 = r_root - rig.base.height_mm / 2

    def x_centre(z: float) -> float:  # rig x of the disk blade's centre plane at rig height z
        return -(z + shift) * math.tan(ha)

    rig_poly = np.array(
        [[x_centre(z_root), z_root], poly[0], poly[1], poly[2], [x_centre(z_top), z_top]]
    )
    R = rotation(ha)
    xz = np.column_stack([rig_poly[:, 0], np.zeros(5), rig_poly[:, 1] + shift]) @ R.T
    return dict(
        alpha=a,
        shift=shift,
        r_in=r_in,
        r_root=r_root,
        r_tip=r_root + rig.blade.height_mm,
        blade_z0=blade_z0,
        platform_right=xz[:, [0, 2]],
    )


def _problem(lay: Layout, n: int) -> tuple[str, float, str, str] | None:
    """The first reason ``n`` blades do not fit this section, as (param, value, allowed, why).

    The platforms cannot cross the sector boundary: in the groove frame they are
    the rig's, whose tip gap :func:`make_layout` already requires.
    """
    rig = lay.params.rig
    g = _geometry(lay, n)
    t, clr = rig.blade.thickness_mm, rig.fit.clearance_mm
    if g["r_root"] < clr + rig.fit.min_feature_mm:
        return (
            "disk.n_blades",
            n,
            "more blades",
            f"the blade roots would reach the disk axis (root radius {g['r_root']:.4g} mm)",
        )
    if g["r_in"] < clr:
        return (
            "disk.n_blades",
            n,
            "more blades",
            f"the hub, rig.base.height_mm = {rig.base.height_mm:g} mm deep, would reach the disk "
            f"axis below blade roots at radius {g['r_root']:.4g} mm; a hub at most "
            f"{g['r_root'] - clr:.4g} mm deep fits {n} blades",
        )
    ha = g["alpha"] / 2
    # the blade's root corner (t/2, blade_z0) must stay inside the sector
    d = g["blade_z0"] * math.sin(ha) - (t / 2) * math.cos(ha)
    if d < clr:
        return (
            "disk.n_blades",
            n,
            "more blades",
            f"the sector angle {math.degrees(g['alpha']):.4g} deg would overlap the blade "
            f"(thickness {t:g} mm) at its root, radius {g['blade_z0']:.4g} mm",
        )
    return None


def _check_damper_clear(lay: Layout, g: dict, n: int) -> None:
    """The seated damper must stay clear of this sector's radial blade.

    Below the platform root the radial blade leans into the groove (it is the
    rig's blade turned by alpha/2 about the root edge). The test is
    conservative: the corner (-x_extent, z_min) of the damper's bounding box
    in the rig frame must lie at least rig.fit.clearance_mm outside the blade.
    By symmetry the next sector's blade is then clear too.
    """
    rig = lay.params.rig
    t, clr = rig.blade.thickness_mm, rig.fit.clearance_mm
    x_ext, z_min = lay.notes["damper_x_extent_mm"], lay.notes["damper_z_min_mm"]
    corner = np.array([-x_ext, 0.0, z_min + g["shift"]]) @ rotation(g["alpha"] / 2).T
    gap = corner[0] - t / 2
    if gap < clr - 1e-9:
        raise InputError(
            "disk.n_blades",
            n,
            "more blades, or a smaller damper",
            f"the damper's lowest corner would come {gap:.3g} mm from the radial blade's face "
            f"(rig.fit.clearance_mm = {clr:g} mm)",
        )


def smallest_n(lay: Layout) -> int:
    """The fewest blades this rig section fits on (InputError if none up to MAX_BLADES)."""
    for n in range(2, MAX_BLADES + 1):
        if _problem(lay, n) is None:
            return n
    raise InputError("rig.blade.thickness_mm", lay.params.rig.blade.thickness_mm, "a thinner blade")


def make_disk_layout(gp: GeometryParams, disk: DiskParams) -> DiskLayout:
    """Seat the damper in the rig's groove and lay the sector out; InputError if it does not fit."""
    n = check_int("disk.n_blades", disk.n_blades, 2, MAX_BLADES)
    lay = make_layout(gp)  # the rig section's and the damper's own checks
    bad = _problem(lay, n)
    if bad is not None:
        if bad[0] == "disk.n_blades":
            n_min = smallest_n(lay)
            bad = ("disk.n_blades", n, f"{n_min} <= disk.n_blades <= {MAX_BLADES}", bad[3])
        raise InputError(*bad)
    g = _geometry(lay, n)
    _check_damper_clear(lay, g, n)
    R = rotation(g["alpha"] / 2)
    shifted = lay.points + np.array([0.0, 0.0, g["shift"]])
    pts = shifted @ R.T
    frames = np.einsum("nki,ji->nkj", lay.frames, R)  # each row vector turned by R
    back = rotation(-g["alpha"])
    image = pts.copy()
    image[lay.side == 1] = pts[lay.side == 1] @ back.T
    rig = gp.rig
    t = rig.blade.thickness_mm

    def on_blade(rec) -> np.ndarray:
        return np.array([-t / 2, rec.y_mm, g["r_root"] + rec.height_mm])

    return DiskLayout(
        disk=disk,
        rig=lay,
        alpha=g["alpha"],
        shift=g["shift"],
        r_in=g["r_in"],
        r_root=g["r_root"],
        r_tip=g["r_tip"],
        blade_z0=g["blade_z0"],
        width=rig.base.width_mm,
        platform_right=g["platform_right"],
        points=pts,
        frames=frames,
        side=lay.side.astype(np.int64),
        image_points=image,
        excitation=on_blade(rig.excitation),
        response=on_blade(rig.response),
    )

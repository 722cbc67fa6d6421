"""Closed-form kinematics of a conical damper in a platform groove (paper eqs 1-6).

The formulas follow "On the efficiency of a conical under-platform damper for
turbines" (Denimal, Wong, Salles, Pesaresi): the inclination of the damper
axis, the platform angle seen in a cross-section of the damper, and the
kinematic slip that the in-phase (radial) relative motion of the platforms
forces along the damper. They are a design-stage estimate;
:mod:`workbench.analytic.rigid` computes the same kinematics exactly in 3-D.

Conventions (DESIGN.md sections 3-4)
------------------------------------
x tangential (blade 1 -> blade 2), y axial (along the damper), z radial
outward. Each platform contact plane contains the y direction and makes the
angle ``beta`` with z; the two planes form a roof over the damper, which the
centrifugal load presses up into it::

        blade 1 platform   z ^   blade 2 platform
                  \\         |         /
                   \\ beta   |  beta  /          view along y
                    \\       |       /
                     \\    .---.    /
                      \\  /     \\  /   damper cross-section
                          \\     /
                           '---'
                                   --> x

The damper is a cone of semi-angle ``alpha_c`` (``cone_angle_deg``), small-end
radius ``R1`` and length ``L`` measured along its axis, so that
``R2 = R1 + L tan(alpha_c)`` and the middle radius is ``Rm = (R1 + R2)/2``.
Its axis lies in the y-z plane, tilted by ``gamma`` from y with the large end
lower (deeper in the groove). The cone touches a plane along a generator
when the angle between its axis and the plane equals ``alpha_c``, which for
both planes at once gives::

    sin(gamma) = sin(alpha_c) / sin(beta)                       (= eq 3)

``alpha_1`` is the angle between a platform trace and the "vertical" of the
plane of a damper cross-section (the plane normal to the axis)::

    tan(alpha_1) = tan(beta) cos(gamma),  tan(alpha_c) = tan(gamma) sin(alpha_1)   (eq 1)

Kinematic slip (eqs 4-6): the platforms move relative to each other by ``v``
along z. Its component in a cross-section is ``v_t = v cos(gamma)``; the
middle section is assumed to roll, which sets the rotation
``theta = v_t / (Rm cos(alpha_1))``; a section of radius ``R`` then lags or
leads the middle one and has to slip::

    s(R) / v = (1 - R / Rm) cos(gamma) / cos(alpha_1)              (eq 6)

zero at the middle, linear along the axis, largest (equal and opposite) at
the two ends: ``s_max / v = (1 - R1/Rm) cos(gamma) / cos(alpha_1)``.

The paper also mentions a longitudinal slip ``s_l = v_s cos(alpha_c)`` without
defining ``v_s``; we read ``v_s = v sin(gamma)``, the part of the platform
motion along the damper axis (:func:`longitudinal_slip_ratio`).

Angles are in degrees and lengths in millimetres at this interface (the
design-stage units of the paper); every result here is a ratio or an angle.
"""

from __future__ import annotations

import dataclasses
import typing
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..config import check_field, param
from ..errors import InputError, check_range

ArrayLike = float | np.ndarray | Sequence[float]

WHY_VERTICAL = (
    "at cone_angle_deg = beta_deg the damper axis would stand vertical (gamma = 90 deg); "
    "above it no cone can touch both platforms"
)


@dataclass(frozen=True)
class ConeDesign:
    """Geometry of a conical damper in its groove (angles in deg, lengths in mm).

    Every field is checked on construction: a bad value raises
    :class:`~workbench.errors.InputError` naming it, its value and the allowed
    range; ``cone_angle_deg`` must also be below ``beta_deg``.
    """

    beta_deg: float = param(
        45.0,
        "platform angle: between each platform contact plane and the radial direction z, deg",
        lo=1.0,
        hi=89.0,
    )  # beyond, the tangency equations are singular to round-off
    cone_angle_deg: float = param(
        10.0, "cone semi-angle alpha_c, deg (0 is a cylinder; must stay below beta_deg)", lo=0.0
    )
    # bounds: a damper of metres (or of nanometres) is no under-platform damper, and beyond
    # them the tangency equations are singular to round-off (1e308: exit 3, not 2)
    r1_mm: float = param(10.0, "small-end radius R1, mm", lo=1.0e-3, hi=1.0e4)
    length_mm: float = param(
        40.0, "damper length L measured along its axis, mm", lo=1.0e-3, hi=1.0e4
    )

    def __post_init__(self) -> None:
        hints = typing.get_type_hints(type(self))
        for f in dataclasses.fields(self):
            if f.name != "cone_angle_deg":
                value = check_field(f, getattr(self, f.name), "", hints[f.name])
                object.__setattr__(self, f.name, value)
        if self.length_mm < 1e-2 * self.r1_mm:  # a disc: its tangency is singular
            raise InputError(
                "length_mm",
                self.length_mm,
                f"length_mm >= 0.01 r1_mm = {1e-2 * self.r1_mm:g} mm",
                "a thinner disc has no defined contact lines",
            )
        # the cone angle's range depends on beta: one message naming both
        ac = check_cone_angle(self.cone_angle_deg, self.beta_deg)
        if ac.ndim != 0:
            raise InputError("cone_angle_deg", self.cone_angle_deg, "a single number")
        object.__setattr__(self, "cone_angle_deg", float(ac))

    @property
    def r2_mm(self) -> float:
        """Large-end radius ``R2 = R1 + L tan(alpha_c)``, mm."""
        return self.r1_mm + self.length_mm * float(np.tan(np.radians(self.cone_angle_deg)))

    @property
    def rm_mm(self) -> float:
        """Middle-section radius ``Rm = (R1 + R2)/2``, mm."""
        return 0.5 * (self.r1_mm + self.r2_mm)

    def replace(self, **changes: float) -> ConeDesign:
        """A copy with some fields changed (checked again)."""
        return dataclasses.replace(self, **changes)


def check_cone_angle(cone_angle_deg: ArrayLike, beta_deg: float) -> np.ndarray:
    """Return the cone angle(s) as an array if ``0 <= alpha_c < beta``, else raise InputError."""
    beta = check_range("beta_deg", beta_deg, 0.0, 90.0, lo_open=True, hi_open=True, unit="deg")
    allowed = f"0 deg <= cone_angle_deg < beta_deg = {beta:g} deg"
    if isinstance(cone_angle_deg, bool):
        raise InputError("cone_angle_deg", cone_angle_deg, allowed, "not a number")
    ac = _as_array("cone_angle_deg", cone_angle_deg, allowed)
    bad = ~((ac >= 0.0) & (ac < beta))
    if bad.any():
        value = float(ac[bad].flat[0])
        raise InputError("cone_angle_deg", value, allowed, WHY_VERTICAL if value >= beta else "")
    return ac


def _as_array(name: str, value: ArrayLike, allowed: str) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(name, value, allowed, "not a number") from None
    if not np.isfinite(arr).all():
        raise InputError(name, value, allowed, "not a finite number")
    return arr


# -- the formulas, on arrays, without checks (callers check) -----------------------------------


def _gamma(ac: np.ndarray, beta: np.ndarray) -> np.ndarray:
    """Inclination gamma (eq 3), radians in and out, accurate to round-off for all 0 <= ac <= beta.

    Eq 3 as printed (an arccos of a number close to 1 for small cone angles)
    loses half the digits there, and asin(sin(ac)/sin(beta)) does the same
    near the vertical. This form is exact at both ends: with
    ``sin^2(beta) - sin^2(ac) = sin(beta - ac) sin(beta + ac)``,
    ``tan(gamma) = sin(ac) / sqrt(sin(beta - ac) sin(beta + ac))``.
    """
    c = np.sqrt(np.clip(np.sin(beta - ac) * np.sin(beta + ac), 0.0, None))
    return np.arctan2(np.sin(ac), c)


def _alpha1(gamma: np.ndarray, beta: np.ndarray) -> np.ndarray:
    """Eq 1 (second relation), radians."""
    return np.arctan(np.tan(beta) * np.cos(gamma))


def _slip_factor(ac_deg, beta_deg) -> np.ndarray:
    """cos(gamma)/cos(alpha_1): eq 6 without the radius term."""
    ac, beta = np.radians(ac_deg), np.radians(beta_deg)
    g = _gamma(ac, beta)
    return np.cos(g) / np.cos(_alpha1(g, beta))


def _max_slip(ac_deg, beta_deg, r1_mm, length_mm) -> np.ndarray:
    """Eq 6 at the ends of the damper, unchecked; valid up to and including alpha_c = beta."""
    r1 = np.asarray(r1_mm, dtype=float)
    r2 = r1 + np.asarray(length_mm, dtype=float) * np.tan(np.radians(ac_deg))
    rm = 0.5 * (r1 + r2)
    return (1.0 - r1 / rm) * _slip_factor(ac_deg, beta_deg)


# -- public, checked ---------------------------------------------------------------------------


def inclination_deg(cone_angle_deg: ArrayLike, beta_deg: float) -> np.ndarray:
    """Inclination ``gamma`` of the damper axis from the y axis (eq 3, see ``_gamma``), deg.

    0 for a cylinder, approaching 90 deg as ``cone_angle_deg`` approaches
    ``beta_deg``. Works on arrays of cone angles.
    """
    ac = check_cone_angle(cone_angle_deg, beta_deg)
    return np.degrees(_gamma(np.radians(ac), np.radians(float(beta_deg))))


def alpha1_deg(cone_angle_deg: ArrayLike, beta_deg: float) -> np.ndarray:
    """Platform angle ``alpha_1`` seen in the plane of a damper cross-section (eq 1), deg."""
    ac = check_cone_angle(cone_angle_deg, beta_deg)
    b = np.radians(float(beta_deg))
    return np.degrees(_alpha1(_gamma(np.radians(ac), b), b))


def section_slip_ratio(design: ConeDesign, position_mm: ArrayLike) -> np.ndarray:
    """Kinematic slip ``s/v`` of the sections at ``position_mm`` along the axis (eqs 5-6).

    ``position_mm`` is measured along the axis from the small end (0 .. L).
    The sign is positive towards the small end (sections smaller than the
    middle one), negative towards the large end; the ratio is per unit
    relative radial displacement ``v`` of the platforms.
    """
    allowed = f"0 <= position_mm <= length_mm = {design.length_mm:g} mm"
    xi = _as_array("position_mm", position_mm, allowed)
    if ((xi < 0.0) | (xi > design.length_mm)).any():
        raise InputError(
            "position_mm", float(xi[(xi < 0) | (xi > design.length_mm)].flat[0]), allowed
        )
    r = design.r1_mm + xi * np.tan(np.radians(design.cone_angle_deg))
    return (1.0 - r / design.rm_mm) * _slip_factor(design.cone_angle_deg, design.beta_deg)


def max_slip_ratio(
    cone_angle_deg: ArrayLike, beta_deg: float, r1_mm: float, length_mm: float
) -> np.ndarray:
    """Largest kinematic slip ratio ``s_max/v`` along the damper (eq 6 at its ends).

    Vectorised over ``cone_angle_deg``; the other inputs are scalars.
    """
    ConeDesign(beta_deg=beta_deg, r1_mm=r1_mm, length_mm=length_mm, cone_angle_deg=0.0)
    ac = check_cone_angle(cone_angle_deg, beta_deg)
    return _max_slip(ac, float(beta_deg), float(r1_mm), float(length_mm))


def longitudinal_slip_ratio(cone_angle_deg: ArrayLike, beta_deg: float) -> np.ndarray:
    """The paper's longitudinal slip ``s_l/v = sin(gamma) cos(alpha_c)``.

    The paper does not define ``v_s``; we read ``v_s = v sin(gamma)``, the
    part of the platforms' relative motion along the damper axis.
    """
    ac = check_cone_angle(cone_angle_deg, beta_deg)
    g = _gamma(np.radians(ac), np.radians(float(beta_deg)))
    return np.sin(g) * np.cos(np.radians(ac))


@dataclass(frozen=True)
class PaperKinematics:
    """Eqs 1-6 evaluated for one design (angles deg, lengths mm, slips per unit ``v``)."""

    design: ConeDesign
    gamma_deg: float
    alpha1_deg: float
    r2_mm: float
    rm_mm: float
    s1_ratio: float  # slip of the small end, s1/v (eq 6)
    s2_ratio: float  # slip of the large end, s2/v (eq 6)
    max_slip_ratio: float  # max(|s1|, |s2|)/v
    longitudinal_slip_ratio: float  # s_l/v, our reading of v_s


def paper_kinematics(design: ConeDesign) -> PaperKinematics:
    """Evaluate the paper's closed-form kinematics for ``design``."""
    ac, b = design.cone_angle_deg, design.beta_deg
    s1, s2 = section_slip_ratio(design, [0.0, design.length_mm])
    return PaperKinematics(
        design=design,
        gamma_deg=float(inclination_deg(ac, b)),
        alpha1_deg=float(alpha1_deg(ac, b)),
        r2_mm=design.r2_mm,
        rm_mm=design.rm_mm,
        s1_ratio=float(s1),
        s2_ratio=float(s2),
        max_slip_ratio=float(max(abs(s1), abs(s2))),
        longitudinal_slip_ratio=float(longitudinal_slip_ratio(ac, b)),
    )

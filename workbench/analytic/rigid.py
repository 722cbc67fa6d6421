"""Exact 3-D rigid-body kinematics of a cone between two platform planes.

A cross-check of the closed-form estimate (:mod:`workbench.analytic.cone`)
that uses no planar approximation. The geometry is built with vectors. The
small rigid motion of the damper comes from a linear constrained
least-squares problem, and the slip is read at every point of both contact
lines.

Geometry (mm; axes x tangential, y axial, z radial, DESIGN.md section 3)
-------------------------------------------------------------------------
The two platform planes meet on the y axis (the ridge of the groove). Plane
``k`` has the unit normal ``n_k`` that points from the platform into the
damper::

    n_0 = ( cos beta, 0, -sin beta)    blade 1 platform, x < 0 (side 0)
    n_1 = (-cos beta, 0, -sin beta)    blade 2 platform, x > 0 (side 1)

The damper axis ``a = (0, cos gamma, -sin gamma)`` runs from the small end to
the large end, with ``a . n_k = sin(alpha_c)``, which is the tangency
condition. The cross-section at axial station ``xi`` (0 at the small end,
``L`` at the large end) has its centre at ``c(xi) = c_m + (xi - L/2) a`` and
radius ``r(xi) = R1 + xi tan(alpha_c)``. It touches plane ``k`` at::

    p_k(xi) = c(xi) + r(xi) m_k,      m_k = (sin(alpha_c) a - n_k) / cos(alpha_c)

because the cone's outward normal there, ``cos(alpha_c) m_k - sin(alpha_c) a``,
equals ``-n_k``. The middle centre ``c_m = (0, 0, -Rm cos(alpha_c)/sin(beta))``
puts every ``p_k(xi)`` in its plane. The pair frame follows
:mod:`workbench.geometry.records`: ``t1`` along the contact line from the
large end to the small end, ``t2 = n x t1``, ``n = n_k``.

Motion
------
The platforms translate rigidly by ``w_0`` and ``w_1``. The in-phase blade
motion is a relative radial displacement ``v = (w_0 - w_1) . z``. The damper
moves by ``u`` (its middle centre) and rotates by a small ``omega``, so a
material point ``p`` moves by ``u + omega x (p - c_m)``. The unknowns
``x = (u, omega)`` obey:

* tangency (4 equations, imposed exactly): every point of each contact line
  keeps zero normal gap, ``n_k . (u + omega x (p - c_m) - w_k) = 0`` at both
  ends of each line. The gap is affine along the line, so two points are
  enough. These equations force ``omega`` along the axis ``a`` (the cone may
  only spin) and leave two free motions: the spin, and a slide along the
  ridge (y);
* rolling of the middle section (4 equations, least squares): the relative
  displacement of the damper at the middle contact point of each line,
  in-plane (``t1``, ``t2``), should vanish.

The transverse (``t2``) part of the rolling condition can be met exactly on
both lines by the spin. The longitudinal (``t1``) part cannot. The tangency
conditions fix the difference of the two lines' longitudinal slips at
``v sin(gamma)/cos(alpha_c)``, so the least-squares solution shares it
equally: ``+-v sin(gamma)/(2 cos(alpha_c))`` on each line, uniform along
it. That is what equal friction limits on the two lines would choose; a
real damper may share it unevenly. Slip is the damper's displacement minus
the platform's at the contact point, in the pair frame, per unit ``|v|``.

Closed form of the result (derived by hand and checked by the tests)::

    transverse slip / v  = (1 - r(xi)/Rm) cos(gamma) / (2 cos(beta) cos(alpha_c))
    longitudinal slip / v = +- sin(gamma) / (2 cos(alpha_c))

so the transverse part is ``cos(alpha_1) / (2 cos(beta) cos(alpha_c))`` times
eq 6: about one half. The factor 1/2 has a simple cause. A cylinder rolling
without slip between two faces that move apart by ``v`` has its centre move
``v/2`` and turns by ``v/(2 R cos(alpha_1))``, like a ball between bearing
races. Eq 4 uses the full ``v``, which is the rotation for a relative
displacement of ``2v``.

Adding a common translation to both platforms adds the same translation to
the damper and changes no slip. So ``w = (+v/2, -v/2)`` (the default here)
and ``w = (v, 0)`` give the same result, and a test checks it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError, SolveError, check_choice, check_int
from .cone import ConeDesign, _gamma, check_cone_angle

SIDES = ("blade 1 platform (x < 0)", "blade 2 platform (x > 0)")


@dataclass(frozen=True)
class ConeInGroove:
    """Exact geometry of a cone tangent to both platform planes (mm).

    ``frames[k]`` has rows ``t1, t2, n`` for the contact line on side ``k``.
    """

    design: ConeDesign
    gamma_rad: float
    axis: np.ndarray  # (3,) unit, small end -> large end
    normals: np.ndarray  # (2, 3) unit platform normals, platform -> damper
    radial: np.ndarray  # (2, 3) unit m_k: section centre -> contact point
    center_mid: np.ndarray  # (3,) mm, centre of the middle section
    frames: np.ndarray  # (2, 3, 3) rows t1, t2, n

    def section_center(self, position_mm: np.ndarray) -> np.ndarray:
        """Centres of the sections at ``position_mm`` from the small end, (n, 3) mm."""
        xi = np.asarray(position_mm, dtype=float)
        return self.center_mid + (xi - 0.5 * self.design.length_mm)[..., None] * self.axis

    def radius(self, position_mm: np.ndarray) -> np.ndarray:
        """Section radii at ``position_mm`` from the small end, mm."""
        xi = np.asarray(position_mm, dtype=float)
        return self.design.r1_mm + xi * np.tan(np.radians(self.design.cone_angle_deg))

    def contact_points(self, position_mm: np.ndarray) -> np.ndarray:
        """Contact points of the sections at ``position_mm``, shape (2, n, 3) mm."""
        c = self.section_center(position_mm)
        r = self.radius(position_mm)
        return c[None] + r[None, :, None] * self.radial[:, None, :]


def groove_geometry(design: ConeDesign) -> ConeInGroove:
    """Place the cone of ``design`` in the groove, tangent to both planes."""
    g = _geometry_arrays(
        np.array([design.cone_angle_deg]), design.beta_deg, design.r1_mm, design.length_mm
    )
    return ConeInGroove(
        design,
        float(g["gamma"][0]),
        g["axis"][0],
        g["normals"][0],
        g["radial"][0],
        g["center_mid"][0],
        g["frames"][0],
    )


def _geometry_arrays(
    ac_deg: np.ndarray, beta_deg: float, r1_mm: float, length_mm: float
) -> dict[str, np.ndarray]:
    """The geometry of :class:`ConeInGroove` for a batch of cone angles (leading axis)."""
    ac, b = np.radians(np.asarray(ac_deg, dtype=float)), np.radians(beta_deg)
    n = ac.size
    gamma = _gamma(ac, b)
    axis = np.stack([np.zeros(n), np.cos(gamma), -np.sin(gamma)], axis=-1)  # (n, 3)
    normals = np.broadcast_to(
        np.array([[np.cos(b), 0.0, -np.sin(b)], [-np.cos(b), 0.0, -np.sin(b)]]), (n, 2, 3)
    )
    sa, ca = np.sin(ac)[:, None, None], np.cos(ac)[:, None, None]
    radial = (sa * axis[:, None, :] - normals) / ca
    t1 = -(axis[:, None, :] - sa * normals) / ca  # along the line, large end -> small end
    frames = np.stack([t1, np.cross(normals, t1), normals], axis=2)  # (n, 2, 3 rows, 3)
    rm = r1_mm + 0.5 * length_mm * np.tan(ac)
    center_mid = np.stack([np.zeros(n), np.zeros(n), -rm * np.cos(ac) / np.sin(b)], axis=-1)
    return dict(
        gamma=gamma,
        axis=axis,
        normals=np.array(normals),
        radial=radial,
        frames=frames,
        center_mid=center_mid,
        rm=rm,
        tan_ac=np.tan(ac),
    )


def in_phase_motion(v_mm: float = 1.0, split: str = "symmetric") -> np.ndarray:
    """Platform displacements (2, 3) mm for a relative radial displacement ``v``.

    ``split``: ``"symmetric"`` moves blade 1's platform by ``+v/2`` and blade
    2's by ``-v/2`` along z; ``"blade2-fixed"`` moves blade 1's by ``+v``;
    ``"blade1-fixed"`` moves blade 2's by ``-v``. All three give the same slip.
    """
    split = check_choice("split", split, ("symmetric", "blade2-fixed", "blade1-fixed"))
    v = float(v_mm)
    top = {"symmetric": (0.5 * v, -0.5 * v), "blade2-fixed": (v, 0.0), "blade1-fixed": (0.0, -v)}
    w = np.zeros((2, 3))
    w[:, 2] = top[split]
    return w


@dataclass(frozen=True)
class RigidBodyKinematics:
    """Small rigid motion of the damper and the slip along both contact lines.

    Slips are displacements of the damper relative to the platform at the
    contact points divided by the size of the platforms' relative
    displacement (``|w_0 - w_1|``, which is ``|v|`` for the in-phase motion).
    """

    geometry: ConeInGroove
    platform_disp_mm: np.ndarray  # (2, 3) the imposed platform translations
    scale_mm: float  # |w_0 - w_1|, the normalisation of the ratios
    translation_mm: np.ndarray  # (3,) of the middle section centre
    rotation_rad: np.ndarray  # (3,) small rotation vector
    position_mm: np.ndarray  # (n,) along the axis from the small end
    points_mm: np.ndarray  # (2, n, 3) contact points
    slip_ratio_local: np.ndarray  # (2, n, 3) in the pair frame: t1 (longitudinal), t2, n (gap)
    middle_residual: np.ndarray  # (2, 2) (t1, t2) slip ratio left at the middle of each line

    @property
    def longitudinal(self) -> np.ndarray:
        """Slip ratio along the contact line (t1, large end -> small end), (2, n)."""
        return self.slip_ratio_local[..., 0]

    @property
    def transverse(self) -> np.ndarray:
        """Slip ratio across the contact line (t2, in the contact plane), (2, n)."""
        return self.slip_ratio_local[..., 1]

    @property
    def slip_ratio(self) -> np.ndarray:
        """Magnitude of the in-plane slip ratio, (2, n)."""
        return np.hypot(self.longitudinal, self.transverse)

    @property
    def max_slip_ratio(self) -> float:
        """Largest in-plane slip ratio over both lines (longitudinal and transverse)."""
        return float(self.slip_ratio.max())

    @property
    def max_transverse_slip_ratio(self) -> float:
        """Largest transverse slip ratio: the quantity eq 6 estimates."""
        return float(np.abs(self.transverse).max())

    @property
    def max_longitudinal_slip_ratio(self) -> float:
        """Largest longitudinal slip ratio (uniform along each line)."""
        return float(np.abs(self.longitudinal).max())

    @property
    def max_gap_ratio(self) -> float:
        """Largest normal gap opened by the motion (should be round-off)."""
        return float(np.abs(self.slip_ratio_local[..., 2]).max())

    @property
    def spin_rad(self) -> float:
        """Rotation about the damper axis, rad (the rolling)."""
        return float(self.rotation_rad @ self.geometry.axis)


def rigid_body_kinematics(
    design: ConeDesign,
    platform_disp_mm: np.ndarray | None = None,
    n_points: int = 23,
) -> RigidBodyKinematics:
    """Solve the small rigid motion of the damper for given platform translations.

    ``platform_disp_mm`` is (2, 3): the translations of the blade 1 and blade 2
    platforms (default :func:`in_phase_motion`, a unit relative radial
    displacement). ``n_points`` contact points per line, evenly spaced
    along the axis from the small end to the large end (paper: 23).
    """
    n = check_int("n_points", n_points, 3, 100_000)
    w = in_phase_motion() if platform_disp_mm is None else _check_disp(platform_disp_mm)
    geo = groove_geometry(design)
    return _solve(geo, w, np.linspace(0.0, design.length_mm, n))


def _check_disp(w: object) -> np.ndarray:
    allowed = "a (2, 3) array of finite platform translations with w[0] != w[1]"
    try:
        arr = np.asarray(w, dtype=float)
    except (TypeError, ValueError):
        raise InputError("platform_disp_mm", w, allowed, "not numbers") from None
    if arr.shape != (2, 3) or not np.isfinite(arr).all():
        raise InputError("platform_disp_mm", w, allowed)
    if not np.linalg.norm(arr[0] - arr[1]) > 0.0:
        raise InputError(
            "platform_disp_mm",
            w,
            allowed,
            "equal translations move the damper rigidly: no slip to compute",
        )
    return arr


def _motion(
    g: dict[str, np.ndarray], length_mm: float, r1_mm: float, w: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Rigid motion x = (u, omega) (n, 6) of a batch of geometries, and the middle residual.

    Rows: the displacement of material point ``p`` is ``u + omega x (p - c_m)``,
    so its component along a unit vector ``e`` is ``[e, (p - c_m) x e] . x``.
    """
    n = g["axis"].shape[0]
    cm, axis, normals, radial = g["center_mid"], g["axis"], g["normals"], g["radial"]

    def point(xi: float) -> np.ndarray:  # (n, 2, 3): contact points of the section at xi
        r = r1_mm + xi * g["tan_ac"]
        return (cm + (xi - 0.5 * length_mm) * axis)[:, None, :] + r[:, None, None] * radial

    def rows(p: np.ndarray, e: np.ndarray) -> np.ndarray:  # (..., 6)
        return np.concatenate([e, np.cross(p - cm[:, None, :], e)], axis=-1)

    ends = (point(0.0), point(length_mm))
    C = np.stack([rows(ends[j], normals)[:, k] for k in range(2) for j in range(2)], axis=1)
    d = np.broadcast_to(
        np.array([normals[0, k] @ w[k] for k in range(2) for _ in range(2)]), (n, 4)
    )
    mid = point(0.5 * length_mm)
    A = np.concatenate(
        [rows(mid[:, k : k + 1, :], g["frames"][:, k, :2]) for k in range(2)], axis=1
    )  # (n, 4, 6): t1, t2 of line 0, then line 1
    b = np.einsum("nkij,kj->nki", g["frames"][:, :, :2], w).reshape(n, 4)

    # Tangency exactly (through the SVD of C), the rolling condition in least squares
    # on the null space of C.
    uc, s, vt = np.linalg.svd(C)
    if np.any(s[:, -1] <= 1e-10 * s[:, 0]):
        raise SolveError(
            f"tangency equations are singular (singular values {s[:, -1]}); "
            "the damper would stand vertical"
        )
    x0 = np.einsum("nji,nj->ni", vt[:, :4], np.einsum("nji,nj->ni", uc, d) / s)
    N = np.swapaxes(vt[:, 4:], 1, 2)  # (n, 6, 2)
    AN = A @ N
    sv = np.linalg.svd(AN, compute_uv=False)
    if np.any(sv[:, -1] <= 1e-10 * np.maximum(sv[:, 0], 1e-300)):
        raise SolveError(
            f"the rolling condition does not fix the damper motion (singular values {sv[:, -1]})"
        )
    z = np.einsum("nij,nj->ni", np.linalg.pinv(AN), b - np.einsum("nij,nj->ni", A, x0))
    x = x0 + np.einsum("nij,nj->ni", N, z)
    resid = (np.einsum("nij,nj->ni", A, x) - b).reshape(n, 2, 2)
    return x, resid


def _solve(geo: ConeInGroove, w: np.ndarray, xi: np.ndarray) -> RigidBodyKinematics:
    d = geo.design
    g = {
        "gamma": np.array([geo.gamma_rad]),
        "axis": geo.axis[None],
        "normals": geo.normals[None],
        "radial": geo.radial[None],
        "frames": geo.frames[None],
        "center_mid": geo.center_mid[None],
        "tan_ac": np.array([np.tan(np.radians(d.cone_angle_deg))]),
    }
    x, resid = _motion(g, d.length_mm, d.r1_mm, w)
    u, omega = x[0, :3], x[0, 3:]
    pts = geo.contact_points(xi)  # (2, n, 3)
    disp = u + np.cross(omega, pts - geo.center_mid) - w[:, None, :]
    scale = float(np.linalg.norm(w[0] - w[1]))
    local = np.einsum("kij,knj->kni", geo.frames, disp) / scale
    return RigidBodyKinematics(
        geometry=geo,
        platform_disp_mm=w,
        scale_mm=scale,
        translation_mm=u,
        rotation_rad=omega,
        position_mm=xi,
        points_mm=pts,
        slip_ratio_local=local,
        middle_residual=resid[0] / scale,
    )


def sweep_cone_angle(
    cone_angle_deg: np.ndarray,
    beta_deg: float,
    r1_mm: float,
    length_mm: float,
) -> dict[str, np.ndarray]:
    """3-D slip ratios for many cone angles (unit in-phase motion; ends and middle only).

    Returns arrays ``max_slip_ratio``, ``max_transverse_slip_ratio`` and
    ``max_longitudinal_slip_ratio`` shaped like ``cone_angle_deg``. Every
    cone angle must lie in ``0 <= alpha_c < beta``. At ``alpha_c = beta`` the
    tangency equations are singular: a vertical cone may also tilt about x
    without opening a gap, to first order.
    """
    base = ConeDesign(beta_deg=beta_deg, cone_angle_deg=0.0, r1_mm=r1_mm, length_mm=length_mm)
    ac = check_cone_angle(cone_angle_deg, base.beta_deg)
    w = in_phase_motion()
    flat = ac.reshape(-1)
    g = _geometry_arrays(flat, base.beta_deg, base.r1_mm, base.length_mm)
    x, _ = _motion(g, base.length_mm, base.r1_mm, w)
    u, omega = x[:, :3], x[:, 3:]
    # the slip is affine along each line: its extremes are at the two ends
    local = []
    for xi in (0.0, base.length_mm):
        r = base.r1_mm + xi * g["tan_ac"]
        p = (g["center_mid"] + (xi - 0.5 * base.length_mm) * g["axis"])[:, None, :] + r[
            :, None, None
        ] * g["radial"]  # (n, 2, 3)
        disp = u[:, None, :] + np.cross(omega[:, None, :], p - g["center_mid"][:, None, :]) - w
        local.append(np.einsum("nkij,nkj->nki", g["frames"], disp))
    local = np.stack(local, axis=2) / float(np.linalg.norm(w[0] - w[1]))  # (n, 2, 2 ends, 3)
    mag = np.hypot(local[..., 0], local[..., 1]).reshape(flat.size, -1)
    return {
        "max_slip_ratio": mag.max(axis=1).reshape(ac.shape),
        "max_transverse_slip_ratio": np.abs(local[..., 1])
        .reshape(flat.size, -1)
        .max(axis=1)
        .reshape(ac.shape),
        "max_longitudinal_slip_ratio": np.abs(local[..., 0])
        .reshape(flat.size, -1)
        .max(axis=1)
        .reshape(ac.shape),
    }

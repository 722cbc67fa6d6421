"""Small hand-made models: the documented examples, the test cases and the benchmark.

* :func:`sdof_jenkins`: one mass on a spring with a Jenkins element to the
  ground (the classic friction oscillator);
* :func:`unit_jenkins`: the same oscillator without units (m = k = 1, the
  peer-code comparison's case);
* :func:`sdof_unilateral`: one mass on a spring pressed on a preloaded
  unilateral spring (it separates when the motion exceeds ``n0 / kn``);
* :func:`two_dof_contact`: a point mass moving in a plane (x tangential, z
  normal) with coupled springs, touching the ground through a 3-D element:
  tangential motion changes the normal load;
* :func:`planar_contact`: the same with a second tangential direction
  (an elliptical tangential motion, for two-dimensional friction laws);
* :func:`line_damper_rig`: a synthetic two-blade rig with a free-free
  damper held by ``2 n_per_line`` contact pairs on two lines, of the size
  of the cone (23 per line) or wedge (73 per line) models of the study of
  the conical damper; its matrices are made of springs and lumped masses,
  not finite elements, but they are dense-sized, the damper is free-free
  (K singular) and the preload balances a centrifugal load.

Every builder returns an :class:`ExampleModel`: the system, the harmonic-1
force per unit level and the output observation.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...contact import ContactElements
from ..core.system import System


@dataclass
class ExampleModel:
    """A system with its excitation (per unit level, N) and outputs."""

    system: System
    f1: np.ndarray  # (n,) complex, N per unit level
    outputs: np.ndarray  # DOF indices or (n_out, n) matrix
    output_names: tuple[str, ...]
    band_hz: tuple[float, float]
    levels: tuple[float, ...]
    info: dict = field(default_factory=dict)


def sdof_jenkins(
    m: float = 0.1,
    f_free_hz: float = 100.0,
    kt_ratio: float = 1.0,
    mu: float = 0.5,
    n0: float = 2.0,
    zeta: float = 0.005,
) -> ExampleModel:
    """Mass ``m`` (kg) on a spring tuned to ``f_free_hz`` with a Jenkins element to the ground.

    ``kt = kt_ratio * k``; slip force ``mu * n0`` (N). Stuck, the natural
    frequency is ``f_free_hz * sqrt(1 + kt_ratio)``.
    """
    k = m * (2 * np.pi * f_free_hz) ** 2
    el = ContactElements.from_dofs(1, [[0]], mu=mu, kt=kt_ratio * k, n0=n0)
    sysm = System(M=[[m]], K=[[k]], zeta=zeta, contacts=el, dof_names=("x",))
    fs = f_free_hz * np.sqrt(1 + kt_ratio)
    return ExampleModel(
        sysm,
        np.array([1.0 + 0j]),
        np.array([0]),
        ("x",),
        (0.8 * f_free_hz, 1.2 * fs),
        (0.2, 0.5, 1.0, 2.0),
        dict(k=k, kt=kt_ratio * k),
    )


def unit_jenkins() -> ExampleModel:
    """The friction oscillator without units: m = 1, k = 1, c = 0.02, kt = 20, mu N = 1.

    Stuck, its natural frequency is sqrt(21) = 4.58 rad/s; the band is
    0.5..3 rad/s (given in "Hz": divided by 2 pi), the levels the peer-code
    comparison's (its continuation stops at once above mu N).
    """
    el = ContactElements.from_dofs(1, [[0]], mu=1.0, kt=20.0, n0=1.0)
    sysm = System(M=[[1.0]], K=[[1.0]], C=[[0.02]], contacts=el, dof_names=("x",))
    return ExampleModel(
        sysm,
        np.array([1.0 + 0j]),
        np.array([0]),
        ("x",),
        (0.5 / (2 * np.pi), 3.0 / (2 * np.pi)),
        (0.6, 0.7, 0.8, 0.9, 1.0),
        dict(k=1.0, kt=20.0),
    )


def sdof_unilateral(
    m: float = 0.1,
    f_free_hz: float = 100.0,
    kn_ratio: float = 1.0,
    n0: float = 1.0,
    zeta: float = 0.01,
) -> ExampleModel:
    """Mass on a spring pressed with ``n0`` (N) on a unilateral spring ``kn = kn_ratio k``.

    The single DOF is the normal direction (positive opening): the contact
    separates when ``x > n0 / kn``. No friction.
    """
    k = m * (2 * np.pi * f_free_hz) ** 2
    el = ContactElements.from_dofs(1, [[-1, -1, 0]], mu=0.0, kt=0.0, kn=kn_ratio * k, n0=n0)
    sysm = System(M=[[m]], K=[[k]], zeta=zeta, contacts=el, dof_names=("z",))
    fc = f_free_hz * np.sqrt(1 + kn_ratio)
    return ExampleModel(
        sysm,
        np.array([1.0 + 0j]),
        np.array([0]),
        ("z",),
        (0.7 * f_free_hz, 1.2 * fc),
        (0.5, 2.0),
        dict(k=k, kn=kn_ratio * k),
    )


def two_dof_contact(
    m: float = 0.1,
    kx: float = 4.0e4,
    kz: float = 8.0e4,
    kxz: float = 2.0e4,
    mu: float = 0.3,
    kt: float = 1.0e5,
    kn: float = 2.0e5,
    n0: float = 5.0,
    zeta: float = 0.01,
    law: str = "decoupled",
) -> ExampleModel:
    """A point mass in the x-z plane on coupled springs, on a 3-D contact element to the ground.

    DOF 0 is x (tangential, t1), DOF 1 is z (normal, positive opening);
    the element has no t2 direction. The coupling ``kxz`` makes the normal
    load follow the tangential motion; at high levels the contact opens.
    """
    K = np.array([[kx, kxz], [kxz, kz]])
    M = np.eye(2) * m
    el = ContactElements.from_dofs(2, [[0, -1, 1]], mu=mu, kt=kt, kn=kn, n0=n0, law=law)
    sysm = System(M=M, K=K, zeta=zeta, contacts=el, dof_names=("x", "z"))
    return ExampleModel(
        sysm,
        np.array([1.0 + 0j, 0.0]),
        np.array([0, 1]),
        ("x", "z"),
        (80.0, 220.0),
        (0.5, 1.0, 2.0, 3.0),
    )


def planar_contact(law: str = "decoupled", level_y: float = 0.7) -> ExampleModel:
    """The two-DOF example with a second tangential direction (x, y tangential, z normal).

    As :func:`two_dof_contact` (m 0.1 kg, kx 4e4, kz 8e4, kxz 2e4 N/m, the
    same element) plus y: ky 4.4e4 N/m, kyz 1e4 N/m. The force on y lags
    the one on x by 90 deg with ``level_y`` of its size, so the tangential
    motion is an ellipse and a two-dimensional law (circular) can lock in
    a force in any direction. Used to check the contact march's history
    rule against run-ups (docs/notes/mean_position.md).
    """
    K = np.array([[4.0e4, 0.0, 2.0e4], [0.0, 4.4e4, 1.0e4], [2.0e4, 1.0e4, 8.0e4]])
    el = ContactElements.from_dofs(3, [[0, 1, 2]], mu=0.3, kt=1.0e5, kn=2.0e5, n0=5.0, law=law)
    sysm = System(M=np.eye(3) * 0.1, K=K, zeta=0.01, contacts=el, dof_names=("x", "y", "z"))
    return ExampleModel(
        sysm,
        np.array([1.0 + 0j, level_y * 1j, 0.0]),
        np.array([0, 1, 2]),
        ("x", "y", "z"),
        (120.0, 230.0),
        (0.5,),
    )


def line_damper_rig(
    n_per_line: int = 23,
    family: str = "out-of-phase",
    cf_n: float = 300.0,
    mu: float = 0.5,
    k_line_n_per_m2: float = 5.0e8,
    length_m: float = 0.04,
    radius_m: float = 0.005,
    beta_deg: float = 45.0,
    zeta: float = 0.002,
) -> ExampleModel:
    """Synthetic two-blade rig with a free-free damper on ``2 n_per_line`` contact pairs.

    Blades: three lumped nodes each (platform, excitation, tip) on springs,
    first bending between 300 and 500 Hz. Platforms: ``n_per_line`` nodes per side on
    springs to the blade's platform node. Damper: a stiff triangular-prism
    truss (the two contact lines and the axis, 3 n_per_line nodes), free-free
    (six rigid-body modes in K). Pair frames: t1 along the damper (y), n the
    platform normal into the damper, preload ``cf_n / (2 n_per_line cos beta)``.
    Excitation: 1 N per unit level in x at each blade's excitation node,
    in phase or out of phase (``family``); output: blade 1 tip x (m).
    """
    n = int(n_per_line)
    b = np.radians(beta_deg)
    nodes: list[np.ndarray] = []
    masses: list[float] = []

    def node(p, mass):
        nodes.append(np.asarray(p, float))
        masses.append(mass)
        return len(nodes) - 1

    blade = []
    for x0 in (-0.02, 0.02):
        blade.append(
            [node((x0, 0.0, 0.10), 0.06), node((x0, 0.0, 0.14), 0.05), node((x0, 0.0, 0.18), 0.04)]
        )
    ys = (np.arange(n) - (n - 1) / 2) * length_m / max(n - 1, 1)
    normals = [np.array([np.sin(b), 0.0, -np.cos(b)]), np.array([-np.sin(b), 0.0, -np.cos(b)])]
    plat = [[node((0, y, 0), 2e-3) for y in ys] for _ in range(2)]
    m_d = 7800 * np.pi * radius_m**2 * length_m
    dline = [
        [node(-radius_m * normals[s] + np.array([0, y, 0]), m_d / (3 * n)) for y in ys]
        for s in range(2)
    ]
    axis = [node((0, y, 0), m_d / (3 * n)) for y in ys]
    nn = len(nodes)
    ndof = 3 * nn
    K = np.zeros((ndof, ndof))
    M = np.diag(np.repeat(masses, 3))

    def dofs(i):
        return np.arange(3 * i, 3 * i + 3)

    def spring(i, j, kx, ky, kz):  # axis-aligned springs between nodes (j = -1: ground)
        kk = np.diag([kx, ky, kz])
        di = dofs(i)
        K[np.ix_(di, di)] += kk
        if j >= 0:
            dj = dofs(j)
            K[np.ix_(dj, dj)] += kk
            K[np.ix_(di, dj)] -= kk
            K[np.ix_(dj, di)] -= kk

    def bar(i, j, ea):  # truss bar along the line between nodes i and j
        d = nodes[j] - nodes[i]
        L = np.linalg.norm(d)
        e = d / L
        kk = ea / L * np.outer(e, e)
        di, dj = dofs(i), dofs(j)
        K[np.ix_(di, di)] += kk
        K[np.ix_(dj, dj)] += kk
        K[np.ix_(di, dj)] -= kk
        K[np.ix_(dj, di)] -= kk

    kb = 0.7e6  # blade bending springs (N/m): stuck in-phase ~340 Hz, out-of-phase ~450 Hz
    for s in range(2):
        a, bb, c = blade[s]
        spring(a, -1, 2 * kb, 4 * kb, 40 * kb)
        spring(bb, a, 1.5 * kb, 3 * kb, 40 * kb)
        spring(c, bb, 1.0 * kb, 2 * kb, 40 * kb)
        for i in range(n):  # platform nodes on the blade's platform node, chained along y
            spring(plat[s][i], a, 2e8 / n, 2e8 / n, 2e8 / n)
            if i:
                spring(plat[s][i], plat[s][i - 1], 1e7, 1e7, 1e7)
    ea = 197e9 * np.pi * radius_m**2 / 3  # steel bars of the damper truss, N
    for i in range(n):
        bar(dline[0][i], dline[1][i], ea)
        bar(dline[0][i], axis[i], ea)
        bar(dline[1][i], axis[i], ea)
        if i:
            for line in (dline[0], dline[1], axis):
                bar(line[i], line[i - 1], ea)
            bar(dline[0][i], dline[1][i - 1], ea)
            bar(dline[0][i], axis[i - 1], ea)
            bar(dline[1][i], axis[i - 1], ea)
    K = 0.5 * (K + K.T)
    # contact pairs: damper node minus platform node in the frame (t1 = y, t2 = n x t1, n)
    frames = []
    d_dofs, p_dofs = [], []
    for s in range(2):
        nv = normals[s]
        t1 = np.array([0.0, 1.0, 0.0])
        t2 = np.cross(nv, t1)
        R = np.stack([t1, t2, nv])
        for i in range(n):
            frames.append(R)
            d_dofs.append(dofs(dline[s][i]))
            p_dofs.append(dofs(plat[s][i]))
    k_node = k_line_n_per_m2 * length_m / n
    n0 = cf_n / (2 * n * np.cos(b))
    el = ContactElements.from_dofs(
        ndof, d_dofs, other=p_dofs, frames=np.array(frames), mu=mu, kt=k_node, kn=k_node, n0=n0
    )
    f1 = np.zeros(ndof, complex)
    sign = 1.0 if family == "in-phase" else -1.0
    f1[dofs(blade[0][1])[0]] = 1.0
    f1[dofs(blade[1][1])[0]] = sign
    sysm = System(M=M, K=K, zeta=zeta, contacts=el)
    out = np.array([dofs(blade[0][2])[0]])
    band = (400.0, 500.0) if family != "in-phase" else (300.0, 380.0)
    return ExampleModel(
        sysm,
        f1,
        out,
        ("blade1_tip_x",),
        band,
        (1.0, 10.0, 30.0),
        dict(n_dofs=ndof, n_pairs=2 * n, preload_n=n0, k_node=k_node),
    )


def write_example_files(folder: str | Path) -> list[Path]:
    """Write the matrices of the documented examples (``.npz``) into ``folder``."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    out = []
    for name, ex in (("sdof_jenkins", sdof_jenkins()), ("two_dof_contact", two_dof_contact())):
        from ...io import atomic_path

        p = folder / f"{name}.npz"
        with atomic_path(p) as tmp:
            with open(tmp, "wb") as fh:
                np.savez(fh, M=ex.system.M, K=ex.system.K)
        out.append(p)
    return out

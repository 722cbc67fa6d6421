"""A mistuned bladed disk from the tuned cyclic sector (issue 32, items 1 and 2).

Mistuning here is a stiffness deviation per blade: sector ``j``'s Young's
modulus is scaled by ``1 + delta_j`` (its blade frequencies by
``sqrt(1 + delta_j)``). The sector mesh has one volume group (hub, platform and
blade are not told apart), so the region scaled is the **whole sector**; the
mass is not changed.

Route (component mode mistuning on the nominal cyclic basis). The tuned disk of
:func:`workbench.pipeline.sector.full_disk_system` is the whole disk on the cyclic
expansion of the sector's per-ND Craig-Bampton bases: sector ``j``'s field is::

    u_j = sum_k cos(j phi_k) E_k^a q_k + sin(j phi_k) E_k^b q_k,   phi_k = 2 pi k / N

``E_k = T_k Phi_k`` the ND-``k`` basis on the extended sector (the right cyclic
face expanded from the left one by ``T_k``; ``E^b = 0`` for ND 0 and N/2). The
mistuned disk's extra strain energy is ``sum_j delta_j u_j^T K_s u_j`` (``K_s``
the sector's FE stiffness), so on the same coordinates::

    dK = Ccc o X^aa + Ccs o X^ab + Csc o X^ba + Css o X^bb

with ``X^ab = E^aT K_s E^b`` (every ND pair at once: the columns of ``E^a`` are
all NDs' ``E_k^a``), ``Ccs[i, m] = sum_j delta_j cos(j phi_k(i)) sin(j phi_k(m))``
and ``o`` the elementwise product. This is the Galerkin projection of the
mistuned FE disk onto the tuned reduced basis, nothing else: with ``delta = 0``
the system is ``full_disk_system``'s exactly, with a uniform ``delta`` it is the
tuned disk with ``(1 + delta) K`` (the cross-ND sums vanish), and the mistuned
eigenvalues are upper bounds of the FE disk's (Rayleigh-Ritz: the reduced space
is a subspace of the FE disk's). Its error against the direct FE solve is the
Craig-Bampton truncation's (measured in tests/test_mistuning.py). The ``X``
blocks are computed once from the sector (``4 n^2`` numbers, ``n`` the number of
sector coordinates over all NDs); a pattern costs ``O(N n^2)``, far below N
sectors' FE work. What it cannot hold: a mistuned shape outside the span of the
tuned modes kept per ND (large or local mistuning, e.g. a cracked blade, needs
more modes per ND or the mistuned sector's own modes).

With friction, :func:`mistuned_forced_response` follows the assembled disk by the
ordinary harmonic balance (condensed onto every damper's contact DOFs), every blade an
output. Linear limits (:func:`linear_blade_response`): ``"none"`` removes the dampers;
``"stuck"`` bonds every contact pair (springs ``kt, kt, kn`` in its frame);
``"free"`` keeps only the normal springs (the frictionless, fully slipping limit
``mu -> 0``). Damping: the tuned model's (modal ratio per ND block), not mistuned.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from ..errors import InputError, check_int
from ..hbm.core.sector import SectorModel
from ..hbm.core.system import System
from .sector import build_sector_model, full_disk_system

DAMPER_LIMITS = ("none", "stuck", "free")


@dataclass(frozen=True)
class MistuningModel:
    """The tuned sector model over every ND ``0..N/2`` and its blade-stiffness projections.

    ``model``: the :class:`SectorModel`; ``cos``, ``sin`` ``(N, n)``: ``cos(j phi_k)``,
    ``sin(j phi_k)`` of sector ``j`` for the ND ``k`` of each sector coordinate (``sin``
    zero for one-copy NDs); ``Xaa, Xab, Xba, Xbb`` ``(n, n)`` N/m: ``E^aT K_s E^a`` etc.;
    ``region``: what a deviation scales.
    """

    model: SectorModel
    cos: np.ndarray
    sin: np.ndarray
    Xaa: np.ndarray
    Xab: np.ndarray
    Xba: np.ndarray
    Xbb: np.ndarray
    region: str = "whole sector"

    @property
    def n_blades(self) -> int:
        return self.model.n_blades

    @property
    def n_sector_dofs(self) -> int:
        """Coordinates of the bladed disk (every ND's), before the dampers'."""
        return int(self.Xaa.shape[0])


def whitehead_bound(n_blades: int) -> float:
    """Whitehead's bound ``(1 + sqrt(N)) / 2`` on the forced-response amplification of a
    mistuned disk with one mode per blade (Whitehead 1966)."""
    n = check_int("n_blades", n_blades, 2)
    return (1.0 + math.sqrt(n)) / 2.0


def check_deviations(deviations, n_blades: int) -> np.ndarray:
    """``deviations`` as an ``(N,)`` float array; InputError (one line) unless there is one
    finite value per blade and every ``1 + delta > 0``."""
    n = check_int("n_blades", n_blades, 2)
    try:
        d = np.asarray(deviations, dtype=float)
    except (TypeError, ValueError):
        raise InputError("deviations", deviations, f"{n} numbers, one per blade") from None
    if d.ndim != 1 or d.shape[0] != n:
        raise InputError("deviations", f"{d.size} values", f"{n} values, one per blade")
    for j, v in enumerate(d):
        if not math.isfinite(v):
            raise InputError(f"deviations[{j}]", float(v), "a finite number")
        if 1.0 + v <= 0.0:
            allowed = "deviations[j] > -1 (blade stiffness (1 + delta) E > 0)"
            raise InputError(f"deviations[{j}]", float(v), allowed)
    return d


def build_mistuning_model(
    rec,
    contact_params,
    n_modes: int = 10,
    n_damper_modes: int = 6,
    zeta: float = 0.005,
    law: str = "decoupled",
) -> MistuningModel:
    """The tuned sector model of DiskSector ``rec`` at every ND ``0..N/2`` (arguments as
    :func:`build_sector_model`) and the projections of the sector stiffness on its bases."""
    keep: dict = {}
    model = build_sector_model(
        rec, contact_params, None, n_modes, n_damper_modes, zeta, law, keep_basis=keep
    )
    Ks = keep["sector"].K
    n_b = model.n_blades
    n_ext = Ks.shape[0]
    cols_a, cols_b, cos_c, sin_c = [], [], [], []
    j = np.arange(n_b)[:, None]
    for k in sorted(model.nd):
        E = keep["basis"][k]
        m = E.shape[1]
        two = model.nd[k].copies == 2
        cols_a.append(E[:n_ext])
        cols_b.append(E[n_ext:] if two else np.zeros((n_ext, m)))
        ph = 2 * math.pi * k * j / n_b
        cos_c.append(np.repeat(np.cos(ph), m, axis=1))
        sin_c.append(np.repeat(np.sin(ph), m, axis=1) if two else np.zeros((n_b, m)))
    Ea, Eb = np.hstack(cols_a), np.hstack(cols_b)
    KEa, KEb = Ks @ Ea, Ks @ Eb
    Xaa, Xbb = Ea.T @ KEa, Eb.T @ KEb
    Xab = Ea.T @ KEb
    return MistuningModel(
        model=model,
        cos=np.hstack(cos_c),
        sin=np.hstack(sin_c),
        Xaa=0.5 * (Xaa + Xaa.T),
        Xab=Xab,
        Xba=np.ascontiguousarray(Xab.T),
        Xbb=0.5 * (Xbb + Xbb.T),
    )


def stiffness_deviation(mm: MistuningModel, deviations) -> np.ndarray:
    """``dK`` ``(n, n)`` N/m on the sector coordinates: the projection of
    ``sum_j delta_j K_s`` (sector ``j``'s) onto the tuned cyclic basis."""
    d = check_deviations(deviations, mm.n_blades)
    c, s = mm.cos, mm.sin
    dc, ds = d[:, None] * c, d[:, None] * s
    dK = (c.T @ dc) * mm.Xaa + (c.T @ ds) * mm.Xab + (s.T @ dc) * mm.Xba + (s.T @ ds) * mm.Xbb
    return 0.5 * (dK + dK.T)


def blade_outputs(mm: MistuningModel, n: int) -> np.ndarray:
    """``(N, n)``: row ``j`` = blade ``j``'s response-point displacement along the excitation
    direction (its own frame), on a disk system of ``n`` coordinates (sector ones first)."""
    model = mm.model
    O = np.zeros((mm.n_blades, n))
    off = 0
    for k in sorted(model.nd):
        blk = model.nd[k]
        m = blk.K.shape[0]
        for j in range(mm.n_blades):
            ph = 2 * math.pi * k * j / mm.n_blades
            row = math.cos(ph) * blk.out[0, 0]
            if blk.copies == 2:
                row = row + math.sin(ph) * blk.out[1, 0]
            O[j, off : off + m] = row
        off += m
    return O


def mistuned_disk_system(
    mm: MistuningModel, deviations, eo: int
) -> tuple[System, np.ndarray, np.ndarray]:
    """The mistuned whole disk: ``full_disk_system(mm.model, eo)`` with ``dK`` added on the
    sector coordinates; ``(System, f1, O)``, ``O`` ``(N, n)`` every blade's response point.
    Zero deviations give ``full_disk_system``'s System unchanged."""
    dK = stiffness_deviation(mm, deviations)
    system, f1, _ = full_disk_system(mm.model, eo)
    n_s = mm.n_sector_dofs
    K = np.array(system.K, dtype=float, copy=True)
    K[:n_s, :n_s] += dK
    return dataclasses.replace(system, K=K), f1, blade_outputs(mm, K.shape[0])


def mistuned_forced_response(
    mm: MistuningModel,
    deviations,
    eo: int,
    force_n: float,
    band_hz: tuple[float, float],
    harmonics: tuple[int, ...] = (0, 1, 2, 3),
    nt: int | None = None,
    options=None,
    label: str = "",
):
    """The friction-damped forced response of the mistuned disk: a
    :class:`workbench.hbm.forced.branch.Branch` over ``band_hz`` whose outputs are the
    ``N`` blades' response points (``blade_0`` ...), by the ordinary harmonic balance on
    :func:`mistuned_disk_system` (condensed onto every damper's contact DOFs).

    ``force_n``: the harmonic-1 force (N) on every blade, blade ``j`` lagging by
    ``j 2 pi eo / N``. ``options``: :class:`SolverOptions` (Hill's stability off unless
    asked for: it is the whole disk's, and costly).
    """
    from ..errors import check_range
    from ..hbm.core.options import SolverOptions
    from ..hbm.forced.response import frequency_response

    force_n = check_range("force", force_n, 0.0, lo_open=True, unit="N")
    lo, hi = (float(v) for v in band_hz)
    check_range("band_hz[0]", lo, 0.0, lo_open=True, unit="Hz")
    check_range("band_hz[1]", hi, lo, lo_open=True, unit="Hz")
    opts = options or SolverOptions(stability=False)
    system, f1, O = mistuned_disk_system(mm, deviations, eo)
    names = tuple(f"blade_{j}" for j in range(mm.n_blades))
    return frequency_response(
        system, f1, force_n, (lo, hi), O, tuple(harmonics), nt, opts, names, label=label
    )


def linear_matrices(mm: MistuningModel, deviations, eo: int, damper: str = "none"):
    """``(K, M, C, f1, O)`` of the mistuned disk in a linear limit ``damper``: "none"
    (dampers removed), "stuck" (contacts bonded: ``kt, kt, kn``) or "free" (normal springs
    only: the frictionless sliding limit)."""
    if damper not in DAMPER_LIMITS:
        raise InputError("damper", damper, "one of " + ", ".join(DAMPER_LIMITS))
    system, f1, O = mistuned_disk_system(mm, deviations, eo)
    K, M, C = np.asarray(system.K), np.asarray(system.M), np.asarray(system.C)
    if damper == "none":
        n = mm.n_sector_dofs
        return K[:n, :n], M[:n, :n], C[:n, :n], f1[:n], O[:, :n]
    ce = system.contacts
    kt = ce.kt1 if damper == "stuck" else 0.0 * ce.kt1
    k_local = np.column_stack([kt, ce.kt2 if damper == "stuck" else kt, ce.kn]).ravel()
    W = ce.W.toarray()
    return K + W.T @ (k_local[:, None] * W), M, C, f1, O


def _solve(K, M, C, f1, O, freqs_hz) -> np.ndarray:
    out = np.zeros((len(freqs_hz), O.shape[0]), dtype=complex)
    for i, f in enumerate(np.asarray(freqs_hz, dtype=float)):
        w = 2 * math.pi * f
        x = sla.solve(K - w * w * M + 1j * w * C, f1, check_finite=False)
        out[i] = O @ x
    return out


def linear_blade_response(
    mm: MistuningModel, deviations, eo: int, freqs_hz, damper: str = "none"
) -> np.ndarray:
    """``(n_freq, N)`` complex receptance (m/N): each blade's response point along the
    excitation direction under a unit engine-order-``eo`` force, in a linear limit
    (``damper``: "none", "stuck" or "free", see :func:`linear_matrices`). Dense solves."""
    return _solve(*linear_matrices(mm, deviations, eo, damper), freqs_hz)


def blade_peaks(
    mm: MistuningModel,
    deviations,
    eo: int,
    band_hz: tuple[float, float],
    damper: str = "none",
    n_freq: int = 100,
) -> tuple[np.ndarray, np.ndarray]:
    """Each blade's peak receptance over ``band_hz`` (m/N) and its frequency (Hz), linear
    limit ``damper``: ``n_freq`` equally spaced points and the undamped natural frequencies
    in the band (a lightly damped peak sits within ``zeta^2`` of one), then the top of every
    blade's grid maximum refined (bounded scalar search to 1e-9 relative in frequency)."""
    from scipy.optimize import minimize_scalar

    lo, hi = (float(v) for v in band_hz)
    if not 0.0 < lo < hi:
        raise InputError("band_hz", band_hz, "0 < band_hz[0] < band_hz[1] (Hz)")
    n_freq = check_int("n_freq", n_freq, 3)
    mats = linear_matrices(mm, deviations, eo, damper)
    w2 = (2 * math.pi * lo) ** 2, (2 * math.pi * hi) ** 2
    lam = sla.eigh(mats[0], mats[1], eigvals_only=True, subset_by_value=w2)
    f = np.union1d(np.linspace(lo, hi, n_freq), np.sqrt(lam) / (2 * math.pi))
    a = np.abs(_solve(*mats, f))
    i_max = np.argmax(a, axis=0)
    peak, at = a[i_max, np.arange(a.shape[1])], f[i_max]
    for b, i in enumerate(i_max):
        lo_b, hi_b = f[max(i - 1, 0)], f[min(i + 1, len(f) - 1)]

        def neg(x, b=b):
            return -abs(_solve(*mats, [x])[0, b])

        opt = {"xatol": 1e-9 * hi}
        r = minimize_scalar(neg, bounds=(lo_b, hi_b), method="bounded", options=opt)
        if -r.fun > peak[b]:
            peak[b], at[b] = -r.fun, r.x
    return peak, at


def tuned_peak(
    mm: MistuningModel, eo: int, band_hz: tuple[float, float], damper: str = "none", n_freq=100
) -> tuple[float, float]:
    """The tuned disk's peak receptance (m/N, every blade alike) and its frequency (Hz)."""
    p, f = blade_peaks(mm, np.zeros(mm.n_blades), eo, band_hz, damper, n_freq)
    j = int(np.argmax(p))
    return float(p[j]), float(f[j])


def mistuned_modes(
    mm: MistuningModel, deviations, damper: str = "none", n: int | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """The undamped mistuned modes in a linear limit: frequencies (Hz, ascending) and each
    mode's blade displacements ``(n_modes, N)`` (response points along the excitation
    direction, modes mass-normalised). ``n``: how many (default all)."""
    K, M, _, _, O = linear_matrices(mm, deviations, 0, damper)
    lam, V = sla.eigh(K, M)
    n = len(lam) if n is None else int(n)
    return np.sqrt(np.clip(lam[:n], 0.0, None)) / (2 * math.pi), (O @ V[:, :n]).T

"""Stability of a periodic solution by Hill's method, three-valued.

A perturbation ``dq = exp(lambda t) p(t)`` of a periodic solution, with
``p`` on the same harmonics, solves Hill's quadratic eigenproblem

    (Delta0 + lambda Delta1 + lambda^2 Delta2) p = 0,
    Delta0 = Z_H + B_H^T D B_H   (the harmonic balance Jacobian on all DOFs),
    Delta1 = C (x) I + 2 M (x) nabla,   Delta2 = M (x) I,

(``nabla`` the time derivative on the harmonics, ``D`` the contact
Jacobian from the AFT). Exponents in 1/s.

Which exponents are Floquet exponents. The exact problem repeats every
exponent shifted by ``i k w`` with its eigenvector shifted by ``-k``
harmonics; the truncated problem keeps only some of the copies, and those
whose eigenvectors lean on the highest retained harmonics are truncation
artefacts (for a non-smooth friction Jacobian they can even have a large
positive real part). The exponents kept are those whose eigenvectors are
the most centred (after Lazarus and Thomas, 2010): with the eigenvector's
content written on complex exponentials ``exp(i k w t)``, ``k = -H..H``,
its mean harmonic index ``kbar`` (weights ``|p_k|^2``) is closest to 0.
Each family of copies has exactly one member with ``|kbar| < 1/2`` when
the truncation is adequate, so the count check is: exactly ``2 n`` of the
``2 n nh`` eigenvalues have ``|kbar| < 1/2`` (``n`` the coordinates).

Verdicts (:data:`STABLE`, :data:`UNSTABLE`, :data:`UNKNOWN`): unstable when
a kept exponent has ``Re > tol * w``; stable when none has and the
selection is trustworthy (count check passed, eigen-solver converged);
unknown otherwise (and when stability is not computed at all).

A second opinion. The friction Jacobian does not always sort the
eigenvectors into clean families: more than ``2 n`` can be centred, and a
family's centred copy may lie far from 0 while its copy near 0 leans on a
harmonic. Both paths therefore also take the exponents of the strip
``|Im lambda| <= w/2`` (:func:`in_strip`, one member per family by
position) and call the point unknown where the two selections reach
opposite verdicts (:func:`second_opinion`); the dense path also where a
dropped centred exponent of the opposite verdict ranks within
:data:`RANK_MARGIN` of the last kept one (:func:`contested`). On the two-DOF
example separating at 3 N, an exponent of real part +18 1/s ranked 0.3 %
behind a stable set, and a time integration started on that orbit leaves
it; on 40 branches of small models (2,621 points) the two paths reached
opposite verdicts at 238 points before this rule and at none after it,
the price being more unknown points. Hill's method with the AFT Jacobian
of a hysteretic law treats the slider's memory as periodic, which is exact
only at ``lambda = 0`` (folds): away from folds its verdict is an
approximation, which these rules make honest, not exact.

Small problems are solved densely (state size ``2 n nh`` up to
``dense_limit``). Larger ones use ARPACK in shift-invert mode about 0 on
the state-space form ``A z = lambda B z``: each application of
``A^-1 B`` needs ``Delta0^-1``, which the Woodbury identity gives from the
LU of the (much smaller) harmonic balance Jacobian the corrector already
works with. A fold (``lambda = 0``), a Neimark-Sacker pair (``lambda = +-i
nu``, ``|nu| <= w/2`` for its centred copy) and a period doubling
(``lambda = i w/2``) all cross the imaginary axis inside the disc
``|lambda| <= w/2``; the sparse path therefore asks for more exponents
until the disc is covered (the farthest exponent found lies beyond
``w/2``), up to a cap: a point whose disc is not covered and where no
unstable exponent was found is ``unknown``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

STABLE, UNSTABLE, UNKNOWN = 1, 0, -1
# a verdict carried to a point from checked neighbours (workbench.hbm.stability.along_path): the
# neighbours' verdict, not established at the point itself
CARRIED_STABLE, CARRIED_UNSTABLE = 2, 3
VERDICT_NAMES = {
    STABLE: "stable",
    UNSTABLE: "unstable",
    UNKNOWN: "unknown",
    CARRIED_STABLE: "stable (carried)",
    CARRIED_UNSTABLE: "unstable (carried)",
}


@dataclass
class Stability:
    """Floquet exponents kept for one solution (1/s) and the verdict."""

    exponents: np.ndarray  # complex, the centred exponents kept
    max_real: float  # largest real part among them (1/s), nan if none
    verdict: int  # STABLE, UNSTABLE or UNKNOWN
    method: str  # "dense" | "arpack" | "none"
    converged: bool = True  # the eigen-solver converged
    count_ok: bool = True  # the centred-eigenvector count check passed
    note: str = ""  # why the verdict is unknown
    start: np.ndarray | None = None  # ARPACK start vector for the next point
    n_exp: int = 0  # exponents ARPACK was asked for
    n_disc: int = 0  # exponents found inside |lambda| <= w/2 (the next point starts near it)

    @property
    def stable(self) -> bool:
        """True only for a trustworthy stable verdict."""
        return self.verdict == STABLE


def unknown(note: str, method: str = "none") -> Stability:
    """The record of a point whose stability was not determined."""
    return Stability(np.zeros(0, complex), float("nan"), UNKNOWN, method, False, False, note)


def mean_harmonic(
    P: np.ndarray, harmonics: tuple[int, ...], moments: bool = False
) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """Mean harmonic index ``kbar`` of each eigenvector (and its RMS index if ``moments``).

    ``P`` (nh, n, m) complex: m eigenvectors on the real Fourier layout of
    :mod:`..core.fourier` (``Q0, Qc_1, Qs_1, ...``). The content at
    ``exp(+- i k w t)`` is ``(Qc -+ i Qs) / 2``; ``kbar = sum k |c_k|^2 /
    sum |c_k|^2`` over ``k = -H..H``.
    """
    num = np.zeros(P.shape[-1])
    sq = np.zeros(P.shape[-1])
    den = np.zeros(P.shape[-1])
    i = 0
    for h in harmonics:
        if h == 0:
            den += np.sum(np.abs(P[i]) ** 2, axis=0)
            i += 1
            continue
        pc, ps = P[i], P[i + 1]
        wp = 0.25 * np.sum(np.abs(pc - 1j * ps) ** 2, axis=0)
        wm = 0.25 * np.sum(np.abs(pc + 1j * ps) ** 2, axis=0)
        num += h * (wp - wm)
        sq += h * h * (wp + wm)
        den += wp + wm
        i += 2
    den = np.maximum(den, 1e-300)
    if moments:
        return num / den, np.sqrt(sq / den)
    return num / den


def _verdict(
    lam: np.ndarray,
    omega: float,
    tol: float,
    trusted: bool,
    note: str,
    found_counts: bool = False,
    **kw,
):
    """STABLE/UNSTABLE when ``trusted``; otherwise UNKNOWN, unless ``found_counts``
    (each exponent in ``lam`` is a genuine centred one) and one of them is unstable."""
    mr = float(np.max(lam.real)) if lam.size else float("nan")
    if lam.size and mr > tol * omega and (trusted or found_counts):
        v = UNSTABLE
    elif trusted:  # (the sparse path may find no centred exponent inside its disc)
        v = STABLE
    else:
        v = UNKNOWN
    return Stability(exponents=lam, max_real=mr, verdict=v, note=note if v == UNKNOWN else "", **kw)


def select_centred(
    lam: np.ndarray, P: np.ndarray, harmonics: tuple[int, ...], n_keep: int
) -> tuple[np.ndarray, np.ndarray, bool]:
    """The ``n_keep`` exponents with the most centred eigenvectors, and the count check.

    ``lam`` (m,) in 1/s, ``P`` (nh, n, m) the eigenvectors.
    Ranked by the RMS harmonic index ``sqrt(sum k^2 |c_k|^2 / sum |c_k|^2)``:
    within a family of copies it is smallest for the copy with
    ``|kbar| <= 1/2`` (shifting by ``m`` adds ``m^2 - 2 m kbar``), and the
    spurious exponents of the truncation lean on the highest harmonics, so
    they rank last. The count check passes when every kept eigenvector is
    the centred copy of its family (``|kbar| < 1/2``: then no two kept
    exponents are copies of each other, so the kept set has one exponent
    per family) and the cut after ``n_keep`` does not split a tie (a
    complex-conjugate pair). Returns (kept exponents, their RMS index,
    check passed).
    """
    kb, rms = mean_harmonic(P, harmonics, moments=True)
    ok = np.isfinite(lam)
    key = np.where(ok, rms, np.inf)
    order = np.argsort(key, kind="stable")
    keep = order[:n_keep]
    count_ok = bool(np.all(ok[keep]) and np.all(np.abs(kb[keep]) < 0.5))
    if order.size > n_keep:
        last, nxt = key[order[n_keep - 1]], key[order[n_keep]]
        count_ok = count_ok and nxt - last > 1e-6 * max(abs(last), 1e-3)
    return lam[keep], rms[keep], count_ok


def hill_eig(d0: np.ndarray, d1: np.ndarray, d2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every eigenvalue (1/s) and eigenvector ``p`` (first half of ``[p; lambda p]``)."""
    n_all = d0.shape[0]
    lu = sla.lu_factor(d2, check_finite=False)
    A = np.zeros((2 * n_all, 2 * n_all))
    A[:n_all, n_all:] = np.eye(n_all)
    A[n_all:, :n_all] = -sla.lu_solve(lu, d0, check_finite=False)
    A[n_all:, n_all:] = -sla.lu_solve(lu, d1, check_finite=False)
    lam, vec = np.linalg.eig(A)
    return lam, vec


def hill_dense(
    d0: np.ndarray,
    d1: np.ndarray,
    d2: np.ndarray,
    omega: float,
    harmonics: tuple[int, ...],
    tol: float = 1e-6,
) -> Stability:
    """All Hill exponents of a small problem from its dense matrices; centred ones kept.

    ``harmonics``: the harmonic list of the layout (``d0`` is ``(nh n, nh n)``,
    harmonic-major, :mod:`..core.fourier`); ``omega`` in rad/s.
    """
    n_all = d0.shape[0]
    lam, vec = hill_eig(d0, d1, d2)
    nh = sum(1 if h == 0 else 2 for h in harmonics)
    n = n_all // nh
    P = vec[:n_all].reshape(nh, n, -1)
    keep, _, count_ok = select_centred(lam, P, harmonics, 2 * n)
    note = (
        "count check failed: the 2n most centred eigenvectors are not one clean set "
        "(too few harmonics for this Jacobian?)"
    )
    if count_ok:
        rival = contested(lam, P, harmonics, 2 * n, omega, tol)
        if rival is not None:
            count_ok = False
            note = (
                f"the verdict hinges on the selection: an exponent of real part {rival.real:.4g} "
                f"1/s, of the other verdict, ranks within {RANK_MARGIN:.0%} of the kept set's "
                "centredness"
            )
    if count_ok:
        other = second_opinion(keep, lam[in_strip(lam, P, harmonics, omega)], omega, tol)
        if other:
            count_ok, note = False, other
    return _verdict(
        keep, omega, tol, count_ok, note, method="dense", converged=True, count_ok=count_ok
    )


RANK_MARGIN = 0.1  # relative RMS-index margin within which a dropped exponent contests the set


def contested(
    lam: np.ndarray,
    P: np.ndarray,
    harmonics: tuple[int, ...],
    n_keep: int,
    omega: float,
    tol: float = 1e-6,
) -> complex | None:
    """A dropped exponent that would reverse the verdict of the kept set and nearly made it.

    With a friction Jacobian the eigenvectors do not always fall into clean
    families: more than ``n_keep`` can be centred (``|kbar| < 1/2``), and the
    ranking by RMS harmonic index then decides between near-equals. When a
    dropped centred exponent whose RMS index is within :data:`RANK_MARGIN`
    of the last kept one is unstable while the kept set is stable, or when
    every unstable kept exponent is that near the cut and as many stable
    rivals are, the verdict rests on that ranking and is not trustworthy;
    this returns a rival (else None).
    """
    kb, rms = mean_harmonic(P, harmonics, moments=True)
    ok = np.isfinite(lam)
    order = np.argsort(np.where(ok, rms, np.inf), kind="stable")
    keep, drop = order[:n_keep], order[n_keep:]
    if not keep.size:
        return None
    cut = rms[keep[-1]]
    bad = lam.real > tol * omega
    near = drop[ok[drop] & (np.abs(kb[drop]) < 0.5) & (rms[drop] <= (1 + RANK_MARGIN) * cut)]
    if not bad[keep].any():  # a stable set: one unstable rival near the cut can reverse it
        rivals = near[bad[near]]
        return complex(lam[rivals[0]]) if rivals.size else None
    # an unstable set is reversed only if every unstable kept exponent is near the cut and
    # as many stable rivals could take their places
    u = keep[bad[keep]]
    rivals = near[~bad[near]]
    if np.all(rms[u] * (1 + RANK_MARGIN) >= cut) and rivals.size >= u.size:
        return complex(lam[rivals[0]])
    return None


STRIP = 0.51  # half-width of the strip |Im lambda| <= STRIP w of the second selection


def in_strip(
    lam: np.ndarray,
    P: np.ndarray,
    harmonics: tuple[int, ...],
    omega: float,
    radius: float | None = None,
) -> np.ndarray:
    """Exponents in the strip ``|Im lambda| <= 0.51 w`` (and ``|lambda| <= radius``, default
    ``w``) whose eigenvectors do not lean on the top harmonics.

    Every family of copies has one member with ``|Im| <= w/2``, whatever its
    eigenvector's mean harmonic; a period doubling's pair sits on the strip's
    edge (``Im = +-w/2``, its ``|lambda|`` just above ``w/2``), hence the margin
    of ``0.01 w``. Truncation artefacts (RMS harmonic index of half the highest
    harmonic or more) and the far exponents of a friction Jacobian (real parts
    about w, beyond ``radius``) are left out. ``radius``: the sparse path's
    search radius (every exponent inside it was found).
    """
    _, rms = mean_harmonic(P, harmonics, moments=True)
    r = omega if radius is None else radius
    return (
        np.isfinite(lam)
        & (np.abs(lam.imag) <= STRIP * omega)
        & (np.abs(lam) <= r)
        & (rms < 0.5 * max(harmonics))
    )


def second_opinion(kept: np.ndarray, strip: np.ndarray, omega: float, tol: float) -> str:
    """Why the verdicts of two selections differ, or "" when they agree.

    ``kept``: the most centred exponents (one per family, by eigenvector);
    ``strip``: those of :func:`in_strip` (one per family, by position). With a
    stick-slip Jacobian the two can pick different members or different
    families (a family whose centred copy lies far from 0 is seen by the
    second only, one whose strip copy leans on a high harmonic by the first
    only); where they reach opposite verdicts, neither is trusted. An empty
    set gives no opinion (with harmonics 0-1 every strip exponent leans on
    the top harmonic).
    """
    a = float(kept.real.max(initial=-np.inf))
    b = float(strip.real.max(initial=-np.inf))
    if not kept.size or not strip.size or (a > tol * omega) == (b > tol * omega):
        return ""
    return (
        f"Hill's two selections disagree: the most centred exponents give max Re {a:.4g} "
        f"1/s, those in the strip |Im lambda| <= {STRIP:g} w give {b:.4g} 1/s"
    )


def _centred(P: np.ndarray, harmonics: tuple[int, ...]) -> np.ndarray:
    """Eigenvectors that are the centred copy of their family and do not lean on the top.

    ``|kbar| < 1/2`` and an RMS harmonic index below half the highest harmonic.
    """
    kb, rms = mean_harmonic(P, harmonics, moments=True)
    return (np.abs(kb) < 0.5) & (rms < 0.5 * max(harmonics))


def hill_arpack(
    size: int,
    op,
    omega: float,
    harmonics: tuple[int, ...],
    n_exp: int = 6,
    tol: float = 1e-6,
    seed: int = 0,
    v0: np.ndarray | None = None,
    n_max: int = 60,
) -> Stability:
    """Hill exponents nearest 0 through ARPACK on ``A^-1 B`` (``op``), covering ``|lambda| <= w/2``.

    Starts with ``n_exp`` exponents (the previous point's final count, along a
    branch) and doubles the count (up to ``n_max``)
    until the farthest one found lies beyond ``w / 2``, so that every
    exponent that can cross the imaginary axis (fold, Neimark-Sacker, period
    doubling) is among those found; keeps those with centred eigenvectors
    (``|kbar| < 1/2``), and takes the second opinion of the strip
    (:func:`in_strip`, out to the farthest exponent found: a period-doubling
    pair, ``|lambda|`` just above ``w/2``, is seen while its real part is
    below about ``0.1 w``, the farthest exponent reaching 0.51-0.56 w on the
    46-pair rig). ``v0``: a start vector, e.g. :attr:`Stability.start`
    of the previous point of a branch.
    """
    from scipy.sparse.linalg import ArpackNoConvergence, LinearOperator, eigs

    L = LinearOperator((size, size), matvec=op, dtype=float)
    nh = sum(1 if h == 0 else 2 for h in harmonics)
    n = size // (2 * nh)
    if v0 is None or v0.shape != (size,) or not np.all(np.isfinite(v0)):
        v0 = np.random.default_rng(seed).standard_normal(size)
    k = min(n_exp, size - 2)
    n_max = min(max(n_max, k), size - 2)
    while True:
        try:
            mu, vec = eigs(
                L,
                k=k,
                which="LM",
                v0=v0,
                ncv=min(size - 1, max(2 * k + 1, 20)),
                # Ritz values to 1e-6 (relative): Re(lambda) within 1e-6 |lambda| <= 1e-6 w/2,
                # below the threshold unstable_tol * w of the verdict
                tol=1e-6,
                maxiter=2000,
            )
        except ArpackNoConvergence as e:
            mu, vec = e.eigenvalues, e.eigenvectors
            nz = np.abs(mu) > 0
            lam = 1.0 / mu[nz]
            P = vec[: nh * n][:, nz].reshape(nh, n, -1) if vec.size else np.zeros((nh, n, 0))
            keep = lam[_centred(P, harmonics)]
            return _verdict(
                keep,
                omega,
                tol,
                False,
                "ARPACK did not converge",
                method="arpack",
                converged=False,
                count_ok=False,
            )
        nz = np.abs(mu) > 0
        lam = 1.0 / mu[nz]
        covered = lam.size > 0 and np.max(np.abs(lam)) > 0.5 * omega
        if covered or k >= n_max:
            break
        k = min(2 * k, n_max)
    start = (vec.real + vec.imag).sum(axis=1)
    n_disc = int(np.sum(np.abs(lam) <= 0.5 * omega))
    P = vec[: nh * n][:, nz].reshape(nh, n, -1)
    keep = lam[_centred(P, harmonics)]
    note = f"the {k} exponents nearest 0 (cap n_floquet_max) do not cover |lambda| <= w/2"
    other = ""
    if covered:  # every exponent out to the farthest found: the strip's are complete there
        strip = lam[in_strip(lam, P, harmonics, omega, radius=float(np.max(np.abs(lam))))]
        other = second_opinion(keep, strip, omega, tol)
        if not keep.size:  # no centred exponent in the disc: the strip's decide alone
            keep = strip
    return _verdict(
        keep,
        omega,
        tol,
        covered and not other,
        other or note,
        found_counts=not covered,
        method="arpack",
        converged=True,
        count_ok=covered and not other,
        start=start,
        n_exp=k,
        n_disc=n_disc,
    )

"""Alternating frequency/time: contact force harmonics from displacement harmonics.

``aft(U, elements, fourier)`` synthesises the local relative displacement
of every element at the ``nt`` samples of a period, marches the contact
law over periods until its state repeats (:func:`workbench.contact.aft_march`),
and analyses the converged period back to harmonics. The Jacobian is the exact
derivative of that discrete march with respect to the harmonics of ``u``.

Arrays: ``U`` (nh, n_el, 3) in metres (layout of :mod:`.fourier`);
the result's ``F`` has the same layout (N), ``J`` is per element
``(n_el, 3, nh, 3, nh)`` = ``dF[h, e, a] / dU[c, e, b]`` at ``[e, a, h, b, c]``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...contact import ContactElements, aft_march, classify
from .fourier import Fourier


@dataclass
class AftResult:
    """Contact forces over one converged period and their harmonics."""

    F: np.ndarray  # (nh, n_el, 3) force harmonics [T1, T2, -N], N
    J: np.ndarray | None  # (n_el, 3, nh, 3, nh) dF/dU, N/m
    u: np.ndarray  # (n_el, nt, 3) displacement samples, m
    f: np.ndarray  # (n_el, nt, 3) force samples, N
    n_slip: np.ndarray  # (n_el,) slipping samples
    n_sep: np.ndarray  # (n_el,) separated samples
    contact: np.ndarray  # (n_el, nt) closed at each sample
    periods: np.ndarray | None = None  # (n_el,) periods marched until the state repeated

    @property
    def status(self) -> np.ndarray:
        """(n_el,) 0 stuck, 1 stick-slip, 2 partial separation, 3 full separation."""
        return classify(self.n_slip, self.n_sep, self.u.shape[1])


def samples(U: np.ndarray, fourier: Fourier) -> np.ndarray:
    """(n_el, nt, 3) time samples of harmonics U (nh, n_el, 3)."""
    nh, n_el, _ = U.shape
    ut = fourier.E @ U.reshape(nh, 3 * n_el)
    return np.ascontiguousarray(ut.reshape(fourier.nt, n_el, 3).transpose(1, 0, 2))


def aft(
    U: np.ndarray, elements: ContactElements, fourier: Fourier, want_jac: bool = True
) -> AftResult:
    """Force harmonics (and their Jacobian) of the contact law for displacement harmonics U."""
    U = np.asarray(U, dtype=float)
    ut = samples(U, fourier)
    out = aft_march(
        ut,
        fourier.E,
        fourier.P,
        elements.mu,
        elements.kt1,
        elements.kt2,
        elements.kn,
        elements.n0,
        elements.law,
        want_jac,
        elements.active,
        elements.lp,
    )
    F = np.ascontiguousarray(out["F"].transpose(2, 0, 1))
    return AftResult(
        F=F,
        J=out["J"],
        u=ut,
        f=out["f"],
        n_slip=out["n_slip"],
        n_sep=out["n_sep"],
        contact=out["contact"],
        periods=out["periods"],
    )


def work_per_cycle(F: np.ndarray, U: np.ndarray, fourier: Fourier) -> np.ndarray:
    """Work per cycle (J) of forces F on displacements U, both (nh, ...): ``int f . du``.

    Each harmonic k contributes ``pi k (Fc_k Us_k - Fs_k Uc_k)``; for the
    sampled contact forces this equals the sum over the samples of
    ``f(t_j) u'(t_j) dt`` exactly, so it closes the energy balance of the
    harmonic balance to round-off.
    """
    w = np.zeros(np.asarray(F).shape[1:])
    for k, c, s in fourier.pairs():
        w = w + np.pi * k * (F[c] * U[s] - F[s] * U[c])
    return w

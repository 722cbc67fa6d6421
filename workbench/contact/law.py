"""The time-domain contact law: the laws of :mod:`.laws` through one generic march.

Per element, with the local relative displacement ``u = [u1, u2, un]``
(metres, ``un > 0`` opening) sampled at ``t_j``:

* normal force ``N_j = max(0, N0 - kn un_j)`` (N, compressive positive;
  DESIGN.md writes ``N0 + kn un`` with ``un`` positive into the contact, the
  same law in the sign convention of ``workbench.geometry.records``);
* tangential force: the law's own rule (``decoupled``: a Jenkins element
  per axis; ``circular``: one circular slip limit; ``dahl``: smooth
  friction), with ``T = 0`` when separated;
* the element starts from rest (slider at ``u = 0``), so an element that
  never slips carries exactly ``kt u``: the stuck linear limit.

The force on the coordinates is ``f = [T1, T2, -N]`` (a restoring force:
the equation of motion reads ``M q'' + C q' + K q + W^T f = p``).

:func:`aft_march` runs the law over periods of the given samples until the
state at the end of a period repeats (:func:`workbench.contact.march.march`)
and returns the harmonics of the force of the converged period and,
exactly, their derivative with respect to the harmonics of ``u``. The time
integration calls the law's ``step`` directly (one sample per time step).
"""

from __future__ import annotations

import numpy as np

from .laws import (
    LAWS,
    SLIP_TOL,  # noqa: F401 - re-exported: the status threshold
)
from .march import march

STUCK, STICK_SLIP, PARTIAL_SEPARATION, FULL_SEPARATION = 0, 1, 2, 3
STATUS_NAMES = ("stuck", "stick-slip", "partial separation", "full separation")


def _law_name(law: int | str) -> str:
    return LAWS[law] if isinstance(law, int | np.integer) else str(law)


def aft_march(
    u: np.ndarray,
    E: np.ndarray,
    P: np.ndarray,
    mu: np.ndarray,
    kt1: np.ndarray,
    kt2: np.ndarray,
    kn: np.ndarray,
    n0: np.ndarray,
    law: int | str,
    want_jac: bool = True,
    active: np.ndarray | None = None,
    lp: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """March the law (name, or its index in ``LAWS``) until the loop repeats; see :func:`march`.

    ``u`` (n_el, nt, 3) in metres; ``E`` (nt, nh) synthesis, ``P`` (nh, nt)
    analysis (:mod:`workbench.hbm.core.fourier`). Returns ``f`` (n_el, nt, 3, N),
    ``F`` (n_el, 3, nh), ``J`` (n_el, 3, nh, 3, nh, N/m) or None, ``n_slip``,
    ``n_sep``, ``contact`` and ``periods`` (periods marched per element). ``lp``
    (n_el, n_own): the law's own parameters per element (default: their defaults).
    """
    name = _law_name(law)
    return march(u, E, P, mu, kt1, kt2, kn, n0, name, want_jac, active=active, lp=lp)


def march_samples(u: np.ndarray, elements) -> dict[str, np.ndarray]:
    """The law of a :class:`ContactElements` over samples ``u`` (n_el, nt, 3) until it repeats.

    Same output as :func:`aft_march` without harmonics (``F``, ``J`` unused).
    """
    nt = np.asarray(u).shape[1]
    return march(
        u,
        np.zeros((nt, 1)),
        np.zeros((1, nt)),
        elements.mu,
        elements.kt1,
        elements.kt2,
        elements.kn,
        elements.n0,
        elements.law,
        want_jac=False,
        lp=elements.lp,
    )


def classify(n_slip: np.ndarray, n_sep: np.ndarray, nt: int) -> np.ndarray:
    """Status per element over a period from the counts of slipping/separated samples.

    0 stuck (never slips, never separates), 1 stick-slip, 2 partial
    separation (separated during part of the period), 3 full separation.
    """
    n_slip = np.asarray(n_slip)
    n_sep = np.asarray(n_sep)
    s = np.where(n_slip > 0, STICK_SLIP, STUCK)
    s = np.where(n_sep > 0, PARTIAL_SEPARATION, s)
    s = np.where(n_sep >= nt, FULL_SEPARATION, s)
    return s.astype(np.int8)

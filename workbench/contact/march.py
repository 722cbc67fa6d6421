"""One contact march for every law: periods of samples until the state repeats.

:func:`march` runs a law (:mod:`workbench.contact.laws`) over periods of
given displacement samples, from rest, until the state at the end of a
period repeats the previous period's end to ``tol`` (relative, per state
entry, to its largest magnitude over the period), at least two periods and
at most ``max_periods`` (a warning when the cap is hit: the loop returned
is then the last one marched, not a converged one). It returns the force
samples of the last period, their harmonics ``P @ f`` and, exactly, their
derivative with respect to the harmonics of the displacement: the chain
rule through every sample of every period marched,

    df_j/dU = Fu E_j + Fs ds_{j-1}/dU,   ds_j/dU = Su E_j + Ss ds_{j-1}/dU.

Where the periodic state is not unique (a stuck element can carry any
locked-in force its slip limit admits over the whole period), the start
picks it. From rest, the decoupled law (and any law whose tangential axes
are independent one-dimensional Jenkins elements) reaches, per axis, the
admissible locked-in force nearest to zero: exactly the state that a
vibration growing slowly from the preload state reaches. A proportional
growth of the motion from rest over any number of periods first
(``growth``: sample ``j`` of growth period ``p`` scaled by
``(p nt + j + 1) / (growth nt)``, the derivative chained through) changes
nothing, to round-off, and the state does not depend on which sample
starts the period (``tests/test_march_history.py``). For the circular law
the start does matter; ``growth`` removes that, but a ramped run-up agrees
better with the march from rest (docs/notes/mean_position.md), so every
law marches from rest and ``growth`` serves the checks.

The march is compiled once per law (:func:`specialise`: the law's ``step``
is a global of its own copy of the kernel, cached on disk by numba under
the name ``_march_<law>``).
"""

from __future__ import annotations

import logging
import types

import numpy as np

from ..errors import InputError
from .law_params import own_params
from .laws import Law, get_law

log = logging.getLogger(__name__)

TOL = 1e-10  # relative repeat tolerance of the end-of-period state
MAX_PERIODS = 200
_warned: set[str] = set()


def specialise(py_func, law: Law, prefix: str, growth: int = 0):
    """A numba-compiled copy of ``py_func`` whose global ``step`` is ``law.step``.

    Each law gets its own function object; ``py_func`` refers to the
    law only through the global names ``step`` and ``growth`` (periods of
    growth from rest), named ``<prefix>_<law>_g<growth>`` (so numba caches one
    compiled kernel per law and growth on disk). Memoised per (function, law,
    growth).
    """
    own = int(growth)
    key = (py_func.__qualname__, law.name, own)
    if key not in _kernels:
        from numba import njit

        g = dict(py_func.__globals__)
        g["step"] = law.step
        g["growth"] = own
        # the growth in the name: numba's disk cache takes globals as constants and would
        # not tell two growths apart
        name = f"{prefix}_{law.name}_g{own}"
        fn = types.FunctionType(py_func.__code__, g, name, py_func.__defaults__)
        fn.__qualname__ = name
        _kernels[key] = njit(cache=True)(fn)
    return _kernels[key]


_kernels: dict = {}
step = None  # the law's step: bound per law by specialise()
growth = 0  # periods of growth from rest: bound per kernel by specialise()


def _march_py(
    ns, u, E, P, mu, kt1, kt2, kn, n0, lp, active, want_jac, tol, max_periods,
    f, F, J, n_slip, n_sep, contact, periods, converged,
):  # fmt: skip
    n_el, nt, _ = u.shape
    nh = E.shape[1]
    m = 3 * nh
    s = np.zeros(ns)
    s_new = np.zeros(ns)
    s_start = np.zeros(ns)
    scale = np.zeros(ns)
    ds = np.zeros((ns, m))
    ds_new = np.zeros((ns, m))
    Fu = np.zeros((3, 3))
    Fs = np.zeros((3, ns))
    Su = np.zeros((ns, 3))
    Ss = np.zeros((ns, ns))
    fj = np.zeros(3)
    uj = np.zeros(3)
    dfb = np.zeros((3, nt, m)) if want_jac else np.zeros((3, 1, m))
    flags = np.zeros(nt, dtype=np.int64)
    for e in range(n_el):
        s[:] = 0.0
        ds[:, :] = 0.0
        # only the directions whose displacement can vary carry derivatives: an inactive
        # direction's displacement is zero and its force acts on nothing (a zero row of W)
        # the columns from the first active direction's block to the last one's: an
        # inactive direction between them keeps zero columns (nothing feeds them)
        lo, hi = m, 0
        for b in range(3):
            if active[e, b]:
                lo = min(lo, b * nh)
                hi = max(hi, (b + 1) * nh)
        # unsigned bounds: indices the compiler knows are not negative (no wrap-around
        # test in the inner loops, which then vectorise)
        ulo, uhi = np.uint64(lo), np.uint64(max(hi, lo))
        lpe = lp[e]  # the element's values of the law's own parameters
        p = 0
        same = False
        # the growth periods first (r < 1: the motion grows from rest, nothing is
        # recorded), then the periodic march (r = 1) until the state repeats
        while p < growth + max_periods:
            growing = p < growth
            s_start[:] = s
            scale[:] = 0.0
            for j in range(nt):
                r = (p * nt + j + 1) / (growth * nt) if growing else 1.0
                for b in range(3):
                    uj[b] = r * u[e, j, b]
                flags[j] = step(
                    uj, s, mu[e], kt1[e], kt2[e], kn[e], n0[e], lpe, want_jac,
                    fj, s_new, Fu, Fs, Su, Ss,
                )  # fmt: skip
                f[e, j, 0] = fj[0]
                f[e, j, 1] = fj[1]
                f[e, j, 2] = fj[2]
                if want_jac:
                    # the law's derivatives are sparse: only their non-zero entries are used,
                    # on the active directions' column blocks and force rows only (contiguous
                    # inner loops over the harmonics, which the compiler vectorises)
                    for a in range(3):
                        if not active[e, a]:  # never read: J's row is zero
                            continue
                        for c in range(ulo, uhi):
                            dfb[a, j, c] = 0.0
                        for k in range(ns):
                            fak = Fs[a, k]
                            if fak != 0.0:
                                for c in range(ulo, uhi):
                                    dfb[a, j, c] += fak * ds[k, c]
                        for b in range(3):
                            fab = Fu[a, b]
                            if fab != 0.0 and active[e, b]:
                                for h in range(nh):
                                    dfb[a, j, b * nh + h] += fab * r * E[j, h]
                    for a in range(ns):
                        for c in range(ulo, uhi):
                            ds_new[a, c] = 0.0
                        for k in range(ns):
                            sak = Ss[a, k]
                            if sak != 0.0:
                                for c in range(ulo, uhi):
                                    ds_new[a, c] += sak * ds[k, c]
                        for b in range(3):
                            sab = Su[a, b]
                            if sab != 0.0 and active[e, b]:
                                for h in range(nh):
                                    ds_new[a, b * nh + h] += sab * r * E[j, h]
                    for a in range(ns):
                        for c in range(ulo, uhi):
                            ds[a, c] = ds_new[a, c]
                for k in range(ns):
                    s[k] = s_new[k]
                    if abs(s[k]) > scale[k]:
                        scale[k] = abs(s[k])
            p += 1
            if p - growth >= 2:
                same = True
                for k in range(ns):
                    if abs(s[k] - s_start[k]) > tol * scale[k]:
                        same = False
                if same:
                    break
        periods[e] = p - growth
        converged[e] = same
        ns_ = 0
        nsep = 0
        for j in range(nt):
            contact[e, j] = flags[j] != 2
            if flags[j] == 1:
                ns_ += 1
            elif flags[j] == 2:
                nsep += 1
        n_slip[e] = ns_
        n_sep[e] = nsep
        F[e] = np.dot(P, f[e]).T
        if want_jac:
            for a in range(3):
                if not active[e, a]:
                    J[e, a] = 0.0
                elif lo == 0 and hi == m:
                    J[e, a] = np.dot(P, dfb[a])
                else:  # the columns lo..hi only (the others are zero)
                    J[e, a] = 0.0
                    sub = np.empty((nt, hi - lo))
                    for j in range(nt):
                        for c in range(lo, hi):
                            sub[j, c - lo] = dfb[a, j, c]
                    Ja = np.dot(P, sub)
                    for h in range(nh):
                        for c in range(lo, hi):
                            J[e, a, h, c] = Ja[h, c - lo]


def law_param_array(law: str, n_el: int, lp: object = None) -> np.ndarray:
    """(n_el, n_own) C-ordered floats: the ``lp`` of law ``law``'s ``step`` per element.

    ``lp`` given: checked for that shape (the compiled step reads it unchecked);
    None: every element at the declared defaults. Zero columns for a law without
    parameters of its own.
    """
    own = own_params(law)
    if lp is None:
        return np.tile(np.array([p.default for p in own], dtype=float), (n_el, 1))
    a = np.ascontiguousarray(lp, dtype=float)
    if a.shape != (n_el, len(own)):
        raise InputError(
            "lp", f"array of shape {a.shape}",
            f"({n_el}, {len(own)}): per element, the {law} law's own parameters "
            f"[{', '.join(p.name for p in own)}]",
        )  # fmt: skip
    return a


def march(
    u: np.ndarray,
    E: np.ndarray,
    P: np.ndarray,
    mu: np.ndarray,
    kt1: np.ndarray,
    kt2: np.ndarray,
    kn: np.ndarray,
    n0: np.ndarray,
    law: str = "decoupled",
    want_jac: bool = True,
    tol: float = TOL,
    max_periods: int = MAX_PERIODS,
    active: np.ndarray | None = None,
    lp: np.ndarray | None = None,
    growth: int = 0,
) -> dict[str, np.ndarray]:
    """March ``law`` over periods of samples ``u`` (n_el, nt, 3) in metres until it repeats.

    ``growth``: periods over which the motion first grows from rest (default 0:
    the march from rest; see the module docstring).

    ``lp`` (n_el, n_own): each element's values of the law's own parameters
    (:func:`law_param_array`; default: their declared defaults).

    ``E`` (nt, nh) synthesises the samples from harmonics, ``P`` (nh, nt)
    analyses them (see :mod:`workbench.hbm.core.fourier`). Returns a dict with

    * ``f`` (n_el, nt, 3): force samples ``[T1, T2, -N]`` (N) of the last period;
    * ``F`` (n_el, 3, nh): their harmonics ``P @ f``;
    * ``J`` (n_el, 3, nh, 3, nh): ``dF[e, a, h] / dU[e, b, c]`` (N/m), or None; only on the
      ``active`` (n_el, 3) directions (default all): zero where the force direction ``a`` or the
      displacement direction ``b`` is inactive (a zero row of ``W``: never moves, acts on
      nothing);
    * ``n_slip``, ``n_sep`` (n_el,): samples slipping / separated in that period;
    * ``contact`` (n_el, nt): the contact is closed (N > 0) at each sample;
    * ``periods`` (n_el,): periods marched; ``converged`` (n_el,): the state repeated
      within ``tol`` (False: the cap was hit, the last period is returned).
    """
    lw = get_law(law)
    u = np.ascontiguousarray(u, dtype=float)
    n_el, nt, _ = u.shape
    nh = E.shape[1]
    f = np.zeros((n_el, nt, 3))
    F = np.zeros((n_el, 3, nh))
    J = np.zeros((n_el, 3, nh, 3 * nh)) if want_jac else np.zeros((1, 3, 1, 3))
    n_slip = np.zeros(n_el, dtype=np.int64)
    n_sep = np.zeros(n_el, dtype=np.int64)
    contact = np.zeros((n_el, nt), dtype=np.bool_)
    periods = np.zeros(n_el, dtype=np.int64)
    converged = np.zeros(n_el, dtype=np.bool_)
    arrs = [np.ascontiguousarray(a, dtype=float) for a in (mu, kt1, kt2, kn, n0)]
    arrs.append(law_param_array(law, n_el, lp))
    act = (
        np.ones((n_el, 3), dtype=np.bool_)
        if active is None
        else np.ascontiguousarray(active, dtype=np.bool_)
    )
    if int(growth) < 0:
        raise InputError("growth", growth, "an integer >= 0 (periods of growth from rest)")
    specialise(_march_py, lw, "_march", growth)(
        lw.n_state, u,
        np.ascontiguousarray(E, dtype=float), np.ascontiguousarray(P, dtype=float),
        *arrs, act, bool(want_jac), float(tol), int(max_periods),
        f, F, J, n_slip, n_sep, contact, periods, converged,
    )  # fmt: skip
    capped = int(np.sum(~converged))
    if capped and law not in _warned:
        _warned.add(law)
        log.warning(
            "contact march (%s law): %d of %d elements did not repeat within %d periods "
            "(tol %g); their last period is used (warned once per law)",
            law, capped, n_el, max_periods, tol,
        )  # fmt: skip
    return dict(
        f=f,
        F=F,
        J=J.reshape(n_el, 3, nh, 3, nh) if want_jac else None,
        n_slip=n_slip,
        n_sep=n_sep,
        contact=contact,
        periods=periods,
        converged=converged,
    )

"""Fourier layout of the harmonic balance: the one place that defines it.

A periodic signal of ``n`` coordinates is kept as real coefficients over a
list of harmonics (DESIGN.md section 3)::

    q(t) = Q0 + sum_k  Qc_k cos(k w t) + Qs_k sin(k w t),   k in harmonics

stored harmonic-major, coordinate fast, in an array ``X`` of shape
``(nh, n)`` (``nh`` = 1 for harmonic 0 plus 2 per harmonic k > 0)::

    component c :   0       1       2       3       4      ...
    part        :   Q0      Qc_1    Qs_1    Qc_2    Qs_2   ...   (harmonics 0,1,2,...)
                  +-------+-------+-------+-------+-------+
    X.ravel()   = | q0..  | qc1.. | qs1.. | qc2.. | qs2.. | ...  X.ravel()[c*n + i]
                  +-------+-------+-------+-------+-------+

A custom list keeps its order sorted (e.g. ``(1, 3, 5)`` has no ``Q0``).
Complex form: the pair ``(Qc_k, Qs_k)`` is ``Q_k = Qc_k - i Qs_k`` so that
``q_k(t) = Re(Q_k exp(i k w t))``; a harmonic force ``Re(F exp(i w t))``
has ``Fc = Re F``, ``Fs = -Im F``.

Time samples: ``t_j = j T / nt`` (``j = 0..nt-1``, ``T = 2 pi / w``);
``x_t = E @ X`` (nt, n) and ``X = P @ x_t`` (exact for ``nt > 2 max(k)``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...errors import InputError, check_int
from ...limits import check_memory


def memory_estimate(harmonics: tuple[int, ...], nt: int, n: int, n_el: int) -> float:
    """Bytes a harmonic balance of this size holds at once (an upper estimate).

    The time grid (``E``, ``P``: nt x nh), the contact samples and their
    derivatives (n_el x nt x 3 and 3 x nt x 3 nh per element), and the dense
    Jacobian on the nonlinear unknowns with its factorisation (two (nh m)^2
    matrices, ``m`` = min(n, 3 n_el) when there are contacts). Hill's
    eigenproblem is left out (it may be sparse): a refusal on this estimate
    is a computation that cannot run, not one that might be tight.
    """
    nh = sum(1 if h == 0 else 2 for h in harmonics)
    m = min(n, 3 * n_el) if n_el else n
    grid = 4 * 8 * nt * nh
    aft = 8 * nt * (7 * n_el + 9 * nh) + 8 * 9 * n_el * nh * nh
    jac = 2 * 8 * (nh * m) ** 2
    return float(grid + aft + jac)


def default_nt(harmonics: tuple[int, ...]) -> int:
    """Samples per period: a power of two >= 16 times the highest harmonic (at least 32)."""
    need = max(32, 16 * max(harmonics))
    return int(2 ** int(np.ceil(np.log2(need))))


@dataclass(frozen=True, eq=False)
class Fourier:
    """A harmonic list and ``nt`` time samples per period, with their matrices."""

    harmonics: tuple[int, ...] = (0, 1, 2, 3)
    nt: int = 0
    k: np.ndarray = field(init=False, repr=False)  # (nh,) harmonic of each component
    kind: np.ndarray = field(init=False, repr=False)  # (nh,) 0 = Q0, 1 = cos, 2 = sin
    E: np.ndarray = field(init=False, repr=False)  # (nt, nh) synthesis
    P: np.ndarray = field(init=False, repr=False)  # (nh, nt) analysis
    # each harmonic k >= 1: (k, cos index, sin index), and the same as index arrays
    _pairs: tuple[tuple[int, int, int], ...] = field(init=False, repr=False)
    ic: np.ndarray = field(init=False, repr=False)  # cos component of each pair
    is_: np.ndarray = field(init=False, repr=False)  # sin component of each pair
    pair_k: np.ndarray = field(init=False, repr=False)  # harmonic of each pair
    pair_row: np.ndarray = field(init=False, repr=False)  # its position in ``harmonics``

    def __post_init__(self) -> None:
        try:
            hs = [check_int("harmonics", h, 0, 10_000) for h in self.harmonics]
        except TypeError:
            raise InputError("harmonics", self.harmonics, "a list of whole numbers >= 0") from None
        if not hs:
            raise InputError("harmonics", list(self.harmonics), "at least one harmonic")
        if len(set(hs)) != len(hs):
            raise InputError("harmonics", list(self.harmonics), "distinct harmonics")
        hs = tuple(sorted(hs))
        if hs == (0,):
            raise InputError("harmonics", list(hs), "at least one harmonic k >= 1")
        nt = self.nt or default_nt(hs)
        nt = check_int("nt", nt, 1)
        if nt <= 2 * max(hs):
            raise InputError(
                "nt", nt, f"nt > 2 * max(harmonics) = {2 * max(hs)} (sampling theorem)"
            )
        nh = sum(1 if h == 0 else 2 for h in hs)
        check_memory(4 * 8 * nt * nh, "nt", nt, f"the {nt} x {nh} time grid of the AFT")
        object.__setattr__(self, "harmonics", hs)
        object.__setattr__(self, "nt", nt)
        k, kind = [], []
        for h in hs:
            if h == 0:
                k.append(0)
                kind.append(0)
            else:
                k += [h, h]
                kind += [1, 2]
        k = np.array(k)
        kind = np.array(kind)
        phase = 2 * np.pi * np.outer(np.arange(nt), k) / nt
        E = np.where(kind == 0, 1.0, np.where(kind == 1, np.cos(phase), np.sin(phase)))
        P = E.T * np.where(kind == 0, 1.0, 2.0)[:, None] / nt
        for name, val in (("k", k), ("kind", kind), ("E", E), ("P", P)):
            val.setflags(write=False)
            object.__setattr__(self, name, val)
        ic = np.flatnonzero(kind == 1)
        object.__setattr__(self, "_pairs", tuple((int(k[c]), int(c), int(c) + 1) for c in ic))
        # index arrays for vectorised work on all pairs at once
        object.__setattr__(self, "ic", ic)
        object.__setattr__(self, "is_", ic + 1)
        object.__setattr__(self, "pair_k", k[ic])
        object.__setattr__(self, "pair_row", np.array([hs.index(int(h)) for h in k[ic]], dtype=int))

    @property
    def nh(self) -> int:
        """Number of real components (1 for harmonic 0, 2 for each k >= 1)."""
        return int(self.k.size)

    @property
    def has_dc(self) -> bool:
        return self.harmonics[0] == 0

    def pairs(self) -> tuple[tuple[int, int, int], ...]:
        """``(k, c, s)``: each harmonic k >= 1 with the indices of its cos and sin parts."""
        return self._pairs

    def index(self, k: int, part: str = "c") -> int:
        """Component index of harmonic ``k``'s part "0", "c" or "s"."""
        want = {"0": 0, "c": 1, "s": 2}[part]
        hit = np.flatnonzero((self.k == k) & (self.kind == want))
        if hit.size == 0:
            raise InputError("harmonic", k, f"one of {list(self.harmonics)}")
        return int(hit[0])

    def nabla(self, omega: float) -> np.ndarray:
        """(nh, nh) time derivative in coefficient space: ``d/dt X = nabla @ X`` (1/s)."""
        D = np.zeros((self.nh, self.nh))
        for k, c, s in self.pairs():
            D[c, s] = k * omega
            D[s, c] = -k * omega
        return D

    def to_complex(self, X: np.ndarray) -> dict[int, np.ndarray]:
        """``{k: Q_k}`` with ``Q_0`` real and ``Q_k = Qc_k - i Qs_k``."""
        out: dict[int, np.ndarray] = {}
        if self.has_dc:
            out[0] = X[0]
        for k, c, s in self.pairs():
            out[k] = X[c] - 1j * X[s]
        return out

    def from_complex(self, Q: dict[int, np.ndarray], shape_tail: tuple[int, ...]) -> np.ndarray:
        """Inverse of :meth:`to_complex` (missing harmonics are zero)."""
        X = np.zeros((self.nh, *shape_tail))
        if self.has_dc and 0 in Q:
            X[0] = np.real(Q[0])
        for k, c, s in self.pairs():
            if k in Q:
                X[c] = np.real(Q[k])
                X[s] = -np.imag(Q[k])
        return X

    def synth(self, X: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """Evaluate at phases ``tau = w t`` (rad): (len(tau), ...) from X (nh, ...)."""
        tau = np.asarray(tau, dtype=float)
        ph = np.outer(tau, self.k)
        B = np.where(self.kind == 0, 1.0, np.where(self.kind == 1, np.cos(ph), np.sin(ph)))
        return np.tensordot(B, X, axes=(1, 0))

    def state_at(
        self, X: np.ndarray, omega: float, t: float = 0.0
    ) -> tuple[np.ndarray, np.ndarray]:
        """Displacement and velocity at time ``t`` (s) of harmonics X (nh, n)."""
        tau = np.array([omega * t])
        return self.synth(X, tau)[0], self.synth(self.nabla(omega) @ X, tau)[0]

    def amplitude(self, X: np.ndarray, n_fine: int = 256) -> np.ndarray:
        """Largest ``|x(t)|`` over the period of each signal in X (nh, m), refined by Newton.

        The trigonometric polynomial is sampled at ``n_fine`` phases, then
        the best sample of each signal is polished with three Newton steps
        on ``x'(t) = 0``, so the result is exact to round-off for any
        harmonic content.
        """
        X = np.atleast_2d(np.asarray(X, dtype=float).T).T
        tau, B0 = self._fine(n_fine)
        x = B0 @ X
        j = np.argmax(np.abs(x), axis=0)
        t = tau[j].copy()
        kk = self.k.astype(float)
        for _ in range(3):
            ph = np.outer(t, kk)
            c, s = np.cos(ph), np.sin(ph)
            # first and second derivatives with respect to the phase
            d1 = np.where(self.kind == 0, 0.0, np.where(self.kind == 1, -kk * s, kk * c))
            d2 = np.where(self.kind == 0, 0.0, np.where(self.kind == 1, -(kk**2) * c, -(kk**2) * s))
            g = np.einsum("mh,hm->m", d1, X)
            hss = np.einsum("mh,hm->m", d2, X)
            ok = np.abs(hss) > 1e-300
            t = np.where(ok, t - np.where(ok, g / np.where(ok, hss, 1.0), 0.0), t)
        ph = np.outer(t, kk)
        B = np.where(self.kind == 0, 1.0, np.where(self.kind == 1, np.cos(ph), np.sin(ph)))
        refined = np.abs(np.einsum("mh,hm->m", B, X))
        return np.maximum(refined, np.abs(x[j, np.arange(x.shape[1])]))

    def _fine(self, n_fine: int) -> tuple[np.ndarray, np.ndarray]:
        """The phases of ``n_fine`` samples and their synthesis matrix (cached per object)."""
        cache = self.__dict__.setdefault("_fine_cache", {})
        if n_fine not in cache:
            tau = 2 * np.pi * np.arange(n_fine) / n_fine
            cache[n_fine] = (tau, self.synth(np.eye(self.nh), tau))
        return cache[n_fine]

    def rms(self, X: np.ndarray) -> np.ndarray:
        """RMS over the period of each signal in X (nh, m).

        ``sqrt(Q0^2 + sum_k (Qc_k^2 + Qs_k^2) / 2)`` (Parseval), same unit as X.
        """
        X = np.asarray(X, dtype=float)
        w = np.where(self.kind == 0, 1.0, 0.5).reshape((-1,) + (1,) * (X.ndim - 1))
        return np.sqrt(np.sum(w * X**2, axis=0))

    def h1_amplitude(self, X: np.ndarray) -> np.ndarray:
        """``sqrt(Qc_1^2 + Qs_1^2)`` of each signal (0 if harmonic 1 is not in the list)."""
        if 1 not in self.harmonics:
            return np.zeros(np.asarray(X).shape[1:])
        c = self.index(1, "c")
        return np.hypot(X[c], X[c + 1])

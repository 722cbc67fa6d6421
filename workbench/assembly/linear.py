"""Linear limits of an assembled model: the stuck and the sliding damper.

Two linear systems bracket every friction-damped response:

* *stuck*: every pair stuck and closed (``K + W^T diag(kt, kt, kn) W``), the
  small-excitation limit;
* *sliding*: tangential forces gone, pairs still closed (``K + W^T diag(0, 0,
  kn) W``), the limit of a damper that slips freely.

For an excitation (an inter-blade phase angle) the *family mode* of each
system is the mode whose modal receptance at the response point is the
largest; its frequency sets the automatic frequency band of the sweeps.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from ..errors import InputError
from .model import AssembledModel


@dataclass(frozen=True)
class FamilyMode:
    """The dominant mode of one linear limit for one excitation pattern."""

    freq_hz: float
    index: int  # mode number (ascending frequency, rigid modes included)
    receptance_m_per_n: float  # |phi_r phi_f| / omega^2 of that mode at the response point


_MODES: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}
_MODES_KEEP = 8


def modes(K: np.ndarray, M: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``scipy.linalg.eigh(K, M)``, remembered for the last few (K, M) pairs (read-only).

    A screen asks for the same pencil up to six times (each family, the
    onset forces, the sliding peak): the dense solve of a 146-pair model is
    about 0.18 s, hashing its matrices about 0.01 s.
    """
    import hashlib

    K = np.ascontiguousarray(K, dtype=float)
    M = np.ascontiguousarray(M, dtype=float)
    h = hashlib.blake2b(digest_size=16)
    for a in (K, M):
        h.update(repr(a.shape).encode())
        h.update(a.data)
    key = h.digest()
    if key not in _MODES:
        lam, phi = sla.eigh(K, M)
        lam.setflags(write=False)
        phi.setflags(write=False)
        if len(_MODES) >= _MODES_KEEP:
            _MODES.pop(next(iter(_MODES)))
        _MODES[key] = (lam, phi)
    return _MODES[key]


def family_frequency(M: np.ndarray, K: np.ndarray, f1: np.ndarray, r: np.ndarray) -> FamilyMode:
    """The mode of ``(K, M)`` with the largest modal receptance from ``f1`` to ``r``.

    Rigid modes (a damper free to slide) carry no resonance and are skipped.
    """
    lam, phi = modes(K, M)
    lam = np.maximum(lam, 0.0)
    scale = np.sqrt(max(lam.max(), 1e-300))
    elastic = np.sqrt(lam) > 1e-6 * scale
    if not elastic.any():
        raise InputError("K", "no elastic mode", "a system with at least one elastic mode")
    contrib = np.zeros(lam.size)
    contrib[elastic] = np.abs((r @ phi[:, elastic]) * (f1 @ phi[:, elastic])) / lam[elastic]
    i = int(np.argmax(contrib))
    return FamilyMode(float(np.sqrt(lam[i]) / (2 * np.pi)), i, float(contrib[i]))


def limit_stiffness(model: AssembledModel, limit: str) -> np.ndarray:
    """Stiffness of the ``"stuck"`` or ``"sliding"`` linear limit (n x n, N/m)."""
    if limit == "stuck":
        kc = np.stack([model.kt, model.kt, model.kn], axis=1)
    elif limit == "sliding":
        kc = np.stack([0 * model.kt, 0 * model.kt, model.kn], axis=1)
    else:
        raise ValueError(f"{limit=} is not 'stuck' or 'sliding'")
    W = model.W
    return model.K + (W.T @ (W.multiply(kc.reshape(-1, 1)))).toarray()


def family_mode(
    model: AssembledModel, phase_deg: float, limit: str, response_blade: int = 1
) -> FamilyMode:
    """The mode that dominates the response to the excitation at ``phase_deg``."""
    return family_frequency(
        model.M,
        limit_stiffness(model, limit),
        model.excitation(phase_deg),
        model.response_dofs[response_blade - 1],
    )


def auto_band(
    model: AssembledModel, phase_deg: float, margin: float, response_blade: int = 1
) -> tuple[float, float, dict[str, float]]:
    """A band holding the family's stuck and sliding resonances, widened by ``margin``."""
    fs = family_mode(model, phase_deg, "stuck", response_blade).freq_hz
    fl = family_mode(model, phase_deg, "sliding", response_blade).freq_hz
    lo, hi = min(fs, fl), max(fs, fl)
    return lo * (1 - margin), hi * (1 + margin), {"stuck_hz": fs, "sliding_hz": fl}

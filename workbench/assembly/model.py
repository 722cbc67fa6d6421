"""Couple a rig and a damper through node-to-node friction contact pairs.

Inputs are two :class:`~workbench.reduced.ReducedModel` records (the rig
with clamped base, the free damper), the :class:`~workbench.geometry.ContactSet`
of the pairs and the :class:`~workbench.assembly.params.ContactParams`.
The output :class:`AssembledModel` is plain numpy/scipy: generalised
coordinates ``q = [q_rig; q_damper]`` with block-diagonal ``M`` and ``K``,
the map ``W`` from ``q`` to each pair's local relative displacement and the
per-pair contact parameters, ready for the harmonic balance solver.

Relative displacement of pair ``i`` in its frame (rows t1, t2, n)::

    u_i = R_i (T_d[i] q_d - T_r[i] q_r)          (damper minus platform)

Normal preload (centrifugal load ``CF`` on the damper, radial +z): the
static balance of a damper pushed into a roof-shaped groove whose faces
make the angle ``beta`` with the radial direction, with friction fully
developed at rest, gives on each side the normal force

    N_side = CF / (2 (sin(beta) + mu cos(beta)))

(for a wedge this is the uniform pressure of the study of the conical
damper, eq. 7, times the face area, with its damper angle equal to
90 deg - beta). Cone and cylinder carry the same total normal force, shared
uniformly along their lines; the wedge shares it in proportion to each
node's tributary area (uniform pressure). The solver then adds the
constant external force that makes ``u = 0`` the static equilibrium of the
preloaded assembly.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from ..contact.elements import ContactElements
from ..errors import InputError, check_range
from ..geometry.records import ContactSet
from ..reduced import ReducedModel
from .params import ContactParams


@dataclass(frozen=True)
class AssembledModel:
    """A rig + damper linear model with its friction contact pairs (SI units)."""

    M: np.ndarray  # (n, n)
    K: np.ndarray  # (n, n), singular when the damper is free
    W: sp.csr_matrix  # (3 n_pairs, n): q -> [t1, t2, n] relative displacement per pair
    mu: np.ndarray  # (n_pairs,)
    kt: np.ndarray  # (n_pairs,) N/m, each tangential direction
    kn: np.ndarray  # (n_pairs,) N/m
    n0: np.ndarray  # (n_pairs,) N, normal preload (compression positive)
    excitation_dofs: np.ndarray  # (2, n): unit force at each blade's excitation point
    response_dofs: np.ndarray  # (2, n): each blade's response displacement from q
    n_rig: int  # q[:n_rig] are rig coordinates
    contact: ContactSet
    info: dict = field(default_factory=dict)
    # each contact law's own parameters beyond mu (workbench/contact/laws/), per pair
    law: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def n(self) -> int:
        return int(self.M.shape[0])

    @property
    def n_pairs(self) -> int:
        return int(self.mu.shape[0])

    def contact_elements(self) -> ContactElements:
        """The contact pairs as the solver's contact elements (one tangential stiffness for
        both directions; the laws' own parameters per pair)."""
        return ContactElements(
            W=self.W,
            mu=self.mu,
            kt1=self.kt,
            kt2=self.kt,
            kn=self.kn,
            n0=self.n0,
            law_params=self.law,
        )

    def excitation(self, phase_deg: float) -> np.ndarray:
        """Complex harmonic-1 force per newton: blade 1 at 0 deg, blade 2 at ``phase_deg``.

        ``f(t) = F Re(f1 e^{i w t})``: 0 deg is the in-phase family, 180 deg
        the out-of-phase family; any inter-blade phase angle is allowed.
        """
        ph = math.radians(check_range("phase_deg", phase_deg, -360.0, 360.0, unit="deg"))
        return self.excitation_dofs[0] + np.exp(1j * ph) * self.excitation_dofs[1]


def side_normal_force(cf_n: float, mu: float, beta_deg: float) -> float:
    """Normal force (N) on each side of the groove that balances ``cf_n`` at rest."""
    b = math.radians(beta_deg)
    return cf_n / (2.0 * (math.sin(b) + mu * math.cos(b)))


def preloads(contact: ContactSet, cf_n: float, mu: float, beta_deg: float) -> np.ndarray:
    """Normal preload (N) of every pair: the same total for every damper shape."""
    n_side = side_normal_force(cf_n, mu, beta_deg)
    n0 = np.empty(contact.n_pairs)
    for s in (0, 1):
        on = contact.side == s
        if not on.any():
            raise InputError("contact.side", s, "pairs on both sides of the groove")
        w = contact.weight[on]
        n0[on] = n_side * w / w.sum()
    return n0


def pair_params(contact: ContactSet, params: ContactParams, beta_deg: float) -> dict:
    """The contact values of every pair (the :class:`AssembledModel` fields ``mu``, ``kt``,
    ``kn``, ``n0`` and ``law``) from the per-unit contact parameters."""
    kt, kn = params.pair_stiffness(contact.kind, contact.weight)
    n = contact.n_pairs
    return {
        "mu": np.full(n, params.mu),
        "kt": kt,
        "kn": kn,
        "n0": preloads(contact, params.cf_n, params.mu, beta_deg),
        "law": {name: np.full(n, value) for name, value in params.law.items()},
    }


def _blade_rows(model: ReducedModel, set_name: str, direction: np.ndarray) -> np.ndarray:
    nodes = np.asarray(model.node_sets[set_name], dtype=int)
    if nodes.size != 2:
        raise InputError(f"rig node set {set_name!r}", nodes.size, "2 nodes (one per blade)")
    rows = np.empty((2, model.n))
    for k, node in enumerate(nodes):
        rows[k] = direction @ model.T[3 * node : 3 * node + 3]
    return rows


def assemble(
    rig: ReducedModel,
    damper: ReducedModel,
    contact: ContactSet,
    params: ContactParams,
    *,
    beta_deg: float,
    excitation_direction: tuple[float, float, float] = (1.0, 0.0, 0.0),
    response_direction: tuple[float, float, float] = (1.0, 0.0, 0.0),
) -> AssembledModel:
    """Build the coupled model; checks that the interface nodes match the pairs."""
    np_ = contact.n_pairs
    rc = np.asarray(rig.node_sets["contact"], dtype=int)
    dc = np.asarray(damper.node_sets["contact"], dtype=int)
    if rc.size != np_ or dc.size != np_:
        raise InputError(
            "contact pairs",
            (rc.size, dc.size),
            f"{np_} rig and damper contact nodes",
            "the reduced models were built for another contact layout",
        )
    gap = max(
        np.abs(rig.node_coords[rc] - contact.points).max(),
        np.abs(damper.node_coords[dc] - contact.points).max(),
    )
    if gap > 1e-7:
        raise InputError(
            "contact node coordinates",
            f"{gap:.3e} m",
            "<= 1e-7 m",
            "the reduced models do not match this contact set",
        )
    nr, nd = rig.n, damper.n
    n = nr + nd
    M = np.zeros((n, n))
    K = np.zeros((n, n))
    M[:nr, :nr], K[:nr, :nr] = rig.M, rig.K
    M[nr:, nr:], K[nr:, nr:] = damper.M, damper.K
    # W rows 3i..3i+2 = R_i [ -T_r(node_i) | T_d(node_i) ]
    blocks = np.empty((np_, 3, n))
    for i in range(np_):
        R = contact.frames[i]
        blocks[i, :, :nr] = -R @ rig.T[3 * rc[i] : 3 * rc[i] + 3]
        blocks[i, :, nr:] = R @ damper.T[3 * dc[i] : 3 * dc[i] + 3]
    Wd = blocks.reshape(3 * np_, n)
    Wd[np.abs(Wd) < 1e-14 * np.abs(Wd).max()] = 0.0
    W = sp.csr_matrix(Wd)
    pairs = pair_params(contact, params, beta_deg)
    exc = np.zeros((2, n))
    exc[:, :nr] = _blade_rows(rig, "excitation", np.asarray(excitation_direction, float))
    resp = np.zeros((2, n))
    resp[:, :nr] = _blade_rows(rig, "response", np.asarray(response_direction, float))
    return AssembledModel(
        M=M,
        K=K,
        W=W,
        **pairs,
        excitation_dofs=exc,
        response_dofs=resp,
        n_rig=nr,
        contact=contact,
        info={
            "n_rig": nr,
            "n_damper": nd,
            "n_pairs": np_,
            "total_preload_n": float(pairs["n0"].sum()),
            "rig_kind": rig.kind,
            "damper_kind": damper.kind,
        },
    )

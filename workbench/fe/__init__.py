"""Finite elements (dolfinx 0.5.2, PETSc, SLEPc): modes and Craig-Bampton reduction.

Data flow::

    BuiltGeometry (rig.msh, damper.msh, contact pairs, named points)
      -> mesh.read_msh            distributed dolfinx mesh, groups by name
      -> elasticity.assemble_body K, M with P2 tetrahedra (base clamped / free)
      -> interface.locate_nodes   the P2 node at each interface point
      -> modes.compute_modes      rig + damper, contacts stuck (springs) or free:
                                  frequencies, first bending pair named, XDMF
      -> reduce.reduce_body       Craig-Bampton (or rigid damper) -> ReducedModel (HDF5)

Public API (imported lazily: ``import workbench.fe`` does not load dolfinx)::

    reduce_body(geom, "rig" | "damper", *, n_modes=12, rigid=False, cache_dir=None,
                comm=None, force=False, timings=None) -> ReducedModel
    compute_modes(geom, *, contact="stuck" | "free", n=10, contact_params=None,
                  comm=None, out_dir=None, shapes=True, timings=None) -> ModesResult
    stuck_reduced_system(rig, damper, contact, params) -> (K, M)     numpy only
    classify_bending(response_disp, excitation_disp=None) -> (labels, i_in, i_out)

Units: SI (m, kg, s, N); frequencies in Hz. Everything runs under
``mpirun``; results do not depend on the number of ranks beyond round-off.
"""

from __future__ import annotations

import importlib
from typing import Any

_LAZY = {
    "reduce_body": "reduce",
    "cached_model": "reduce",
    "code_version": "reduce",
    "load_contact": "reduce",
    "save_model": "reduce",
    "compute_modes": "modes",
    "classify_bending": "modes",
    "ModesResult": "modes",
    "BodyShapes": "modes",
    "stuck_reduced_system": "coupling",
    "pair_springs": "coupling",
}

__all__ = sorted(_LAZY)


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

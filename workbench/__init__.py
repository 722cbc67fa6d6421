"""upd-workbench: finite element and harmonic balance workbench for turbine
under-platform friction dampers (wedge, cylinder, cone).

The sub-packages follow the data flow::

    analytic  -> closed-form cone kinematics (design stage, no FE)
    geometry  -> gmsh rig and damper meshes with matched contact nodes
    fe        -> dolfinx/SLEPc modes and Craig-Bampton ReducedModel (HDF5)
    contact   -> node-to-node 3-D friction law, vectorised
    hbm       -> AFT, residual/Jacobian, SNES corrector, continuation, Hill
    assembly  -> rig + damper + contact pairs + preload + excitation
    pipeline  -> a case's model (geometry -> fe -> assembly, cached) and its curve
    studies   -> study TOML runner: cases, cache, resume, MPI
    post      -> receptances, energies, contact status, tables
    render    -> pyvista / matplotlib figures and the HTML report
    cli       -> the ``upd`` command

Nothing below ``fe`` imports dolfinx or gmsh.
"""

import os as _os

# numba colours its messages with colorama when colorama is installed (pyNastran
# brings it); colorama's exit hook then writes an escape code to stdout, which breaks
# ``upd ... --json`` (seen under mpirun). Plain messages are enough for us.
_os.environ.setdefault("NUMBA_DISABLE_ERROR_MESSAGE_HIGHLIGHTING", "1")

__version__ = "0.1.0"

__all__ = [
    "__version__",
    "Model",
    "model",
    "frf",
    "receptance_figure",
    "status_figure",
    "energy_figure",
    "peak_figure",
    "study",
    "load_results",
    "frf_model",
    "frf_curves",
    "frf_figure",
    "read_matrices",
    "sector_frf",
]

# The Python API (workbench/api.py, docs/API.md), loaded on first use so that
# ``import workbench`` stays light and touches neither dolfinx nor matplotlib.
_API = (
    "Model",
    "model",
    "frf",
    "receptance_figure",
    "status_figure",
    "energy_figure",
    "peak_figure",
    "study",
    "load_results",
    "frf_model",
    "frf_curves",
    "frf_figure",
    "read_matrices",
    "sector_frf",
)


def __getattr__(name: str):
    if name in _API:
        from . import api

        return getattr(api, name)
    raise AttributeError(f"module 'workbench' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *_API])

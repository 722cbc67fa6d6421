"""Versions of the software a result was computed with (for reports and HDF5)."""

from __future__ import annotations

import importlib
import platform

from . import __version__

_MODULES = (
    "numpy",
    "scipy",
    "dolfinx",
    "petsc4py",
    "slepc4py",
    "mpi4py",
    "gmsh",
    "h5py",
    "matplotlib",
    "pyvista",
    "vtk",
)


def software_versions(import_heavy: bool = False) -> dict[str, str]:
    """Name -> version of this package, Python and its main dependencies.

    Modules not yet imported are looked up through package metadata only,
    unless ``import_heavy`` is set, so calling this does not load dolfinx.
    """
    import sys
    from importlib import metadata

    out = {"upd-workbench": __version__, "python": platform.python_version()}
    dist_names = {"dolfinx": "fenics-dolfinx", "gmsh": None, "vtk": "vtk"}
    for name in _MODULES:
        ver = None
        mod = sys.modules.get(name)
        if mod is None and import_heavy:
            try:
                mod = importlib.import_module(name)
            except Exception:  # noqa: BLE001 - a missing optional module is not an error
                mod = None
        if mod is not None:
            ver = getattr(mod, "__version__", None)
            if name == "vtk" and ver is None:
                try:
                    ver = mod.vtkVersion.GetVTKVersion()
                except AttributeError:
                    ver = None
        if ver is None:
            dn = dist_names.get(name, name)
            if dn:
                try:
                    ver = metadata.version(dn)
                except metadata.PackageNotFoundError:
                    ver = None
        if ver is not None:
            out[name] = str(ver)
    return out

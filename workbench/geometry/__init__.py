"""gmsh builders for the blade rig and the dampers (cone, cylinder, wedge: :mod:`.shapes`).

``build_geometry(damper, out_dir, ...)`` resolves the parameters
(``geometry/*.toml``), seats the damper in the groove and checks that it
fits (:mod:`.layout`, pure numpy), draws and meshes the rig and the damper
with gmsh (:mod:`.occ`) and returns a :class:`BuiltGeometry`.
:func:`read_msh` loads a written mesh into dolfinx (with group names).

Importing this package does not import gmsh or dolfinx; the builders do.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from .build import build_geometry, code_version, geometry_digest
from .layout import Layout, make_layout
from .params import GeometryParams, load_geometry_params
from .records import BuiltGeometry, ContactSet


def __getattr__(name: str) -> Any:
    """``DAMPERS``: the names of the registered damper shapes (:mod:`.shapes`), in order."""
    if name == "DAMPERS":
        from .shapes import names

        return names()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def read_msh(path: str | Path, comm: Any = None, rank: int = 0) -> Any:
    """Load a written ``.msh`` into dolfinx: a :class:`~.mshio.DolfinxMesh`
    (mesh, cell and facet tags, group names, point-group coordinates).

    Use this instead of ``dolfinx.io.gmshio.read_from_msh``, which is broken
    in Debian's dolfinx 0.5.2 (see :mod:`.mshio`). Imports dolfinx.
    """
    from .mshio import read_msh as _read

    return _read(path, comm, rank)


__all__ = [
    "DAMPERS",
    "BuiltGeometry",
    "ContactSet",
    "GeometryParams",
    "Layout",
    "build_geometry",
    "code_version",
    "geometry_digest",
    "load_geometry_params",
    "make_layout",
    "read_msh",
]

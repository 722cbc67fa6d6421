"""Records handed from the geometry stage to the finite element stage.

Axes (DESIGN.md section 3): x tangential (blade 1 -> blade 2), y axial (along
the damper), z radial (outward, along the blade span). Lengths in metres.

Contact pairs
-------------
A contact pair ``i`` is a damper node and a platform node at the same point
``points[i]``. Its local frame ``frames[i]`` has rows ``t1, t2, n``:

* ``n``  unit outward normal of the platform face, pointing from the
  platform into the damper;
* ``t1`` unit vector along the contact line (the damper generator for cone
  and cylinder; +y for the wedge), oriented from the damper's large end to
  its small end (cone) or towards +y (cylinder, wedge);
* ``t2 = n x t1`` in the contact plane, so (t1, t2, n) is right-handed.

The relative displacement of pair ``i`` in its frame is
``u_i = frames[i] @ (u_damper - u_platform)``: ``u_i[2] < 0`` pushes the
damper into the platform (compression).

Order of the pairs::

    side 0 (platform of blade 1, x < 0)   pairs 0 .. n-1
    side 1 (platform of blade 2, x > 0)   pairs n .. 2n-1

Within a side: along the line from the large end to the small end (cone; as
in the paper, points 1 and 24 at the large section), from -y to +y
(cylinder); for the wedge a row-major grid, ``n_y`` along y (fast index)
times ``n_s`` rows up the slope.

The wedge grid is staggered: row 0 (the lowest) has ``n_y`` points, the
rows alternate ``n_y`` and ``n_y - 1`` points, the short rows sitting
between the points of the full rows (default 5 rows of 15/14/15/14/15 = 73
per face, 146 pairs, as in the paper). Points sit at the middles of equal
segments (lines) or strips (faces); ``weight`` is each point's tributary
length or area (its nearest-point cell), summing per side to the line
length or face area.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np


@dataclass(frozen=True)
class ContactSet:
    """Matched contact points with their frames, sides and tributary weights."""

    points: np.ndarray  # (n_pairs, 3) m
    frames: np.ndarray  # (n_pairs, 3, 3) rows t1, t2, n
    side: np.ndarray  # (n_pairs,) int: 0 blade 1 platform, 1 blade 2 platform
    weight: np.ndarray  # (n_pairs,) tributary length (m, lines) or area (m^2, faces)
    kind: str  # "line" (cone, cylinder) or "face" (wedge)

    ARRAYS = ("points", "frames", "side", "weight")

    @property
    def n_pairs(self) -> int:
        return int(self.points.shape[0])

    def write_h5(self, group) -> None:
        """Write the arrays into an HDF5 group (the kind is the caller's to store)."""
        for name in self.ARRAYS:
            group[name] = getattr(self, name)

    @classmethod
    def read_h5(cls, group, kind: str) -> ContactSet:
        """The contact set written by :meth:`write_h5` into ``group``, of ``kind``."""
        return cls(**{name: group[name][()] for name in cls.ARRAYS}, kind=kind)

    def __post_init__(self) -> None:
        n = self.points.shape[0]
        assert self.points.shape == (n, 3), self.points.shape
        assert self.frames.shape == (n, 3, 3), self.frames.shape
        assert self.side.shape == (n,) and self.weight.shape == (n,)
        assert self.kind in ("line", "face"), self.kind


@dataclass(frozen=True)
class BuiltGeometry:
    """What ``workbench.geometry.build`` returns and ``upd mesh`` writes.

    ``rig_msh`` and ``damper_msh`` are second-order gmsh meshes with named
    physical groups (see ``workbench.geometry``); every contact point is a
    mesh node of both. Points named in rig.toml (excitation, response) are
    mesh nodes of the rig; ``excitation_points[k]``/``response_points[k]``
    lie on blade ``k + 1``.
    """

    damper: str  # a registered shape's name (workbench.geometry.shapes): "cone", ...
    rig_msh: Path
    damper_msh: Path
    contact: ContactSet
    excitation_points: np.ndarray  # (2, 3) m, one per blade
    response_points: np.ndarray  # (2, 3) m, one per blade
    excitation_direction: np.ndarray  # (3,) unit vector of the excitation force
    response_direction: np.ndarray  # (3,) unit vector of the measured displacement
    damper_volume_m3: float
    damper_mass_kg: float
    damper_centroid: np.ndarray  # (3,) m
    material: dict[str, float]  # E_pa, nu, rho_kg_m3
    params: dict[str, Any]  # the rig and damper inputs (nested, file units)
    digest: str  # hash of params + code version: the cache key
    stats: dict[str, Any] = field(default_factory=dict)  # n_nodes, n_cells, gaps, ...

    def save(self, path: str | Path) -> Path:
        """Write the record as ``geometry.h5`` (arrays) beside the meshes."""
        import h5py

        from ..io import atomic_path

        path = Path(path)
        with atomic_path(path) as tmp, h5py.File(tmp, "w") as h:
            h.attrs["damper"] = self.damper
            h.attrs["rig_msh"] = str(Path(self.rig_msh).name)
            h.attrs["damper_msh"] = str(Path(self.damper_msh).name)
            h.attrs["contact_kind"] = self.contact.kind
            h.attrs["damper_volume_m3"] = self.damper_volume_m3
            h.attrs["damper_mass_kg"] = self.damper_mass_kg
            h.attrs["material"] = json.dumps(self.material)
            h.attrs["params"] = json.dumps(self.params)
            h.attrs["digest"] = self.digest
            h.attrs["stats"] = json.dumps(self.stats, default=float)
            self.contact.write_h5(h.require_group("contact"))
            h["excitation_points"] = self.excitation_points
            h["response_points"] = self.response_points
            h["excitation_direction"] = self.excitation_direction
            h["response_direction"] = self.response_direction
            h["damper_centroid"] = self.damper_centroid
        return path

    @classmethod
    def load(cls, path: str | Path) -> BuiltGeometry:
        """Read a record written by :meth:`save`; mesh paths are resolved beside it."""
        import h5py

        path = Path(path)
        with h5py.File(path, "r") as h:
            a = h.attrs
            contact = ContactSet.read_h5(h["contact"], str(a["contact_kind"]))
            return cls(
                damper=str(a["damper"]),
                rig_msh=path.parent / str(a["rig_msh"]),
                damper_msh=path.parent / str(a["damper_msh"]),
                contact=contact,
                excitation_points=h["excitation_points"][()],
                response_points=h["response_points"][()],
                excitation_direction=h["excitation_direction"][()],
                response_direction=h["response_direction"][()],
                damper_volume_m3=float(a["damper_volume_m3"]),
                damper_mass_kg=float(a["damper_mass_kg"]),
                damper_centroid=h["damper_centroid"][()],
                material=json.loads(a["material"]),
                params=json.loads(a["params"]),
                digest=str(a["digest"]),
                stats=json.loads(a["stats"]),
            )

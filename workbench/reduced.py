"""The reduced linear model of one body: the hand-over point of the pipeline.

Everything downstream (contact, harmonic balance, studies, plots) works on
:class:`ReducedModel` records and plain numpy; nothing here imports dolfinx
or gmsh, so a user can bring reduced matrices from any FE code.

A body's generalised coordinates ``q`` (length ``n``) obey
``M q'' + K q = T^T f`` where ``f`` stacks the forces at its interface nodes.
The interface node displacements are::

    u = (T @ q).reshape(n_nodes, 3)          # rows x, y, z of each node

For a Craig-Bampton model ``q = [u_b (3 n_nodes, node-major x,y,z); eta (m)]``
and ``T = [I, 0]``; for a rigid damper ``q = [u_ref (3); theta (3)]`` about
the reference point ``ref_point`` and ``T`` stacks ``[I, -skew(x_i - ref)]``.

Interface node order (``node_sets`` gives the index arrays):

* rig: the platform nodes of every contact pair in ContactSet order
  ("contact"), then the excitation points of blades 1, 2 ("excitation"),
  then the response points of blades 1, 2 ("response");
* damper: the damper nodes of every contact pair in ContactSet order.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .io import atomic_path


@dataclass(frozen=True)
class ReducedModel:
    """Reduced mass and stiffness of one body, with its interface nodes."""

    name: str  # "rig" | "damper"
    kind: str  # "craig-bampton" | "rigid" | "modal" | "user"
    K: np.ndarray  # (n, n) N/m (and N m/rad for rotations)
    M: np.ndarray  # (n, n) kg
    T: np.ndarray  # (3 n_nodes, n) interface node displacements from q
    node_coords: np.ndarray  # (n_nodes, 3) m
    node_sets: dict[str, np.ndarray]  # name -> indices into node_coords
    mode_freqs_hz: np.ndarray = field(default_factory=lambda: np.zeros(0))  # fixed-interface
    ref_point: np.ndarray = field(default_factory=lambda: np.zeros(3))  # rigid bodies
    inputs: dict[str, Any] = field(default_factory=dict)  # canonical inputs that made it
    digest: str = ""  # hash of ``inputs`` and the code version
    code_version: str = ""
    n_full_dofs: int = 0  # DOFs of the finite element model it came from
    timings: dict[str, float] = field(default_factory=dict)  # stage -> seconds

    @property
    def n(self) -> int:
        return int(self.K.shape[0])

    @property
    def n_nodes(self) -> int:
        return int(self.node_coords.shape[0])

    def node_dofs(self, nodes: np.ndarray | list[int]) -> np.ndarray:
        """Rows of ``T`` for the x, y, z displacements of ``nodes`` (node-major)."""
        nodes = np.asarray(nodes, dtype=int)
        return (3 * nodes[:, None] + np.arange(3)[None, :]).ravel()

    def check(self) -> None:
        """Real finite matrices whose shapes agree, K and M symmetric, M positive definite
        (ValueError otherwise; a reduced model read from a file is checked before use)."""
        n = self.n
        for name in ("K", "M", "T", "node_coords"):
            A = np.asarray(getattr(self, name))
            if A.dtype.kind not in "iuf" or A.ndim != 2 or not np.all(np.isfinite(A)):
                raise ValueError(f"{self.name}: {name} is not a real finite matrix")
        if self.K.shape != (n, n) or self.M.shape != (n, n):
            raise ValueError(f"{self.name}: K {self.K.shape} and M {self.M.shape} differ")
        if self.T.shape != (3 * self.n_nodes, n):
            raise ValueError(f"{self.name}: T is {self.T.shape}, not {(3 * self.n_nodes, n)}")
        for name, A in (("K", self.K), ("M", self.M)):
            scale = max(np.abs(A).max(), 1e-300)
            asym = np.abs(A - A.T).max() / scale
            if asym > 1e-8:
                raise ValueError(f"{self.name}: {name} is not symmetric ({asym=:.2e})")
        np.linalg.cholesky(self.M)

    def save(self, path: str | Path) -> Path:
        """Write to HDF5 atomically."""
        import h5py

        path = Path(path)
        with atomic_path(path) as tmp, h5py.File(tmp, "w") as h:
            for k in ("K", "M", "T", "node_coords", "mode_freqs_hz", "ref_point"):
                h.create_dataset(k, data=getattr(self, k))
            g = h.create_group("node_sets")
            for k, v in self.node_sets.items():
                g.create_dataset(k, data=np.asarray(v, dtype=np.int64))
            h.attrs["name"] = self.name
            h.attrs["kind"] = self.kind
            h.attrs["inputs"] = json.dumps(self.inputs, sort_keys=True, default=str)
            h.attrs["digest"] = self.digest
            h.attrs["code_version"] = self.code_version
            h.attrs["n_full_dofs"] = self.n_full_dofs
            h.attrs["timings"] = json.dumps(self.timings)
            from .io.units import REDUCED_UNITS, annotate

            annotate(h, REDUCED_UNITS)
        return path

    @classmethod
    def load(cls, path: str | Path) -> ReducedModel:
        import h5py

        with h5py.File(path, "r") as h:
            a = h.attrs
            return cls(
                name=str(a["name"]),
                kind=str(a["kind"]),
                K=h["K"][()],
                M=h["M"][()],
                T=h["T"][()],
                node_coords=h["node_coords"][()],
                node_sets={k: v[()] for k, v in h["node_sets"].items()},
                mode_freqs_hz=h["mode_freqs_hz"][()],
                ref_point=h["ref_point"][()],
                inputs=json.loads(a["inputs"]),
                digest=str(a["digest"]),
                code_version=str(a["code_version"]),
                n_full_dofs=int(a["n_full_dofs"]),
                timings=json.loads(a["timings"]),
            )

    @staticmethod
    def peek_digest(path: str | Path) -> str | None:
        """The digest stored in a file, or None if it is missing or unreadable."""
        try:
            import h5py

            with h5py.File(path, "r") as h:
                return str(h.attrs["digest"])
        except (OSError, KeyError):
            return None

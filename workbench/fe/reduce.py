"""``reduce_body``: a BuiltGeometry body -> a cached :class:`~workbench.reduced.ReducedModel`.

* rig: Craig-Bampton onto its interface nodes (every contact pair's
  platform node, the excitation and response points), base clamped;
* damper: Craig-Bampton onto its contact nodes (free-free: the interface
  pins the rigid-body motion, which the constraint modes carry exactly;
  the reduced damper is checked to have exactly six zero eigenvalues), or
  the rigid 6-DOF damper (``rigid=True``).

Each model is saved as ``<cache_dir>/<body>_<method>_<digest>.h5``; the
digest covers the geometry digest, the options and the FE code version
(:func:`code_version`, a hash of this package's sources), so a changed
input or code gives a new file and an unchanged one is read back. The
HDF5 file also holds the contact set (``contact/points``, ``frames``,
``side``, ``weight``, ``kind``) beside the ReducedModel datasets.
"""

from __future__ import annotations

import logging
import time
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError, SolveError, check_choice, check_int
from ..io import atomic_path, digest
from ..io import code_version as _code_version
from ..log import stage
from ..reduced import ReducedModel
from .parallel import info

log = logging.getLogger(__name__)

_SOURCES = (
    "reduce.py",
    "craig_bampton.py",
    "rigid.py",
    "elasticity.py",
    "interface.py",
    "mesh.py",
    "solvers.py",
    "parallel.py",
    "pads.py",
    "block_eigen.py",  # the fixed-interface eigen solve (was missing from the key)
    "modes.py",  # load_bodies
)
N_MODES_MAX = 500
RIGID_RATIO = 1e-6  # six eigenvalues below this fraction of the first elastic one


def code_version() -> str:
    """Package version plus a hash of the FE sources that produce a reduced model."""
    return _code_version(Path(__file__).resolve().parent, _SOURCES, "fe")


def reduce_inputs(geom, body: str, n_modes: int, rigid: bool) -> dict[str, Any]:
    """The canonical inputs of a reduced model (what its digest covers, with the code)."""
    from .interface import interface_points

    pts, sets, _ = interface_points(geom, body)
    return {
        "geometry_digest": geom.digest,
        "damper": geom.damper,
        "body": body,
        "method": "rigid" if rigid else "craig-bampton",
        "n_modes": 0 if rigid else int(n_modes),
        "material": dict(geom.material),
        "n_interface_nodes": int(len(pts)),
        "interface_points_digest": digest(np.round(pts, 12).tolist()),
    }


def model_path(cache_dir: Path, inputs: dict[str, Any], dig: str) -> Path:
    method = "rigid" if inputs["method"] == "rigid" else f"cb{inputs['n_modes']}"
    return Path(cache_dir) / f"{inputs['body']}_{method}_{dig}.h5"


def model_digest(geom, body: str, n_modes: int, rigid: bool) -> tuple[dict[str, Any], str]:
    """(canonical inputs, digest) of a reduced model: what decides whether a cache matches."""
    inputs = reduce_inputs(geom, body, n_modes, rigid)
    return inputs, digest({"inputs": inputs, "code": code_version()})


def cached_model(
    geom, body: str, *, n_modes: int = 12, rigid: bool = False, cache_dir: str | Path
) -> Path | None:
    """The cached file of this model if it exists with the right digest, else None."""
    inputs, dig = model_digest(geom, body, n_modes, rigid)
    path = model_path(Path(cache_dir), inputs, dig)
    return path if ReducedModel.peek_digest(path) == dig else None


def save_model(rm: ReducedModel, path: str | Path, contact=None) -> Path:
    """Write a ReducedModel (and the ContactSet, if given) to HDF5 atomically."""
    import h5py

    path = Path(path)
    with atomic_path(path) as tmp:
        rm.save(tmp)
        if contact is not None:
            with h5py.File(tmp, "a") as h:
                g = h.create_group("contact")
                contact.write_h5(g)
                g.attrs["kind"] = contact.kind
    return path


def load_contact(path: str | Path):
    """The ContactSet stored beside a reduced model, or None."""
    import h5py

    from ..geometry.records import ContactSet

    with h5py.File(path, "r") as h:
        if "contact" not in h:
            return None
        g = h["contact"]
        return ContactSet.read_h5(g, str(g.attrs["kind"]))


def reduce_body(
    geom,
    body: str,
    *,
    n_modes: int = 12,
    rigid: bool = False,
    cache_dir: str | Path | None = None,
    comm=None,
    force: bool = False,
    timings: dict[str, float] | None = None,
) -> ReducedModel:
    """Reduce the rig or the damper of ``geom`` (a BuiltGeometry); cached under ``cache_dir``.

    ``n_modes``: fixed-interface modes kept (Craig-Bampton). ``rigid``: the
    rigid 6-DOF damper instead (damper only). ``force``: recompute even if
    a cached model matches. Every rank returns the same model; rank 0 writes
    the file.
    """
    from mpi4py import MPI

    comm = MPI.COMM_WORLD if comm is None else comm
    body = check_choice("body", body, ("rig", "damper"))
    n_modes = check_int("n_modes", n_modes, 0, N_MODES_MAX)
    if rigid and body != "damper":
        raise InputError("rigid", rigid, "false for the rig", "only the damper can be rigid")
    inputs, dig = model_digest(geom, body, n_modes, rigid)
    code = code_version()
    path = model_path(Path(cache_dir), inputs, dig) if cache_dir is not None else None
    if path is not None and not force:
        rm = comm.bcast(_load_if_current(path, dig) if comm.rank == 0 else None)
        if rm is not None:
            info(log, comm, "%s: reusing %s (digest %s)", body, path, dig)
            return rm
    info(log, comm, "%s: building the %s model (digest %s)", body, inputs["method"], dig)
    t0 = time.perf_counter()
    timings = {} if timings is None else timings
    if rigid:
        rm = _rigid_damper(geom, inputs, dig, code, comm, timings)
    else:
        rm = _craig_bampton(geom, body, n_modes, inputs, dig, code, comm, timings)
    timings["total"] = time.perf_counter() - t0
    rm = _with_timings(rm, timings)
    try:
        rm.check()
    except (AssertionError, ValueError, np.linalg.LinAlgError) as e:
        raise SolveError(f"{body}: the reduced model fails its check ({e})", partial=rm) from e
    if path is not None:
        if comm.rank == 0:
            save_model(rm, path, geom.contact)
        comm.Barrier()
        info(log, comm, "%s: wrote %s", body, path)
    return rm


def _load_if_current(path: Path, dig: str) -> ReducedModel | None:
    """The cached model if its digest matches and it reads back whole, else None."""
    if ReducedModel.peek_digest(path) != dig:
        if path.is_file() and ReducedModel.peek_digest(path) is None:
            log.warning("%s is unreadable; rebuilding it", path)
        return None
    try:
        rm = ReducedModel.load(path)
        rm.check()  # its matrices reach LAPACK and PETSc: a damaged file is rebuilt instead
        return rm
    except (OSError, KeyError, ValueError, TypeError, np.linalg.LinAlgError) as e:
        log.warning("%s is unreadable (%s); rebuilding it", path, e)
        return None


def _with_timings(rm: ReducedModel, timings: dict[str, float]) -> ReducedModel:
    import dataclasses

    return dataclasses.replace(rm, timings={k: round(float(v), 4) for k, v in timings.items()})


def _rigid_damper(geom, inputs, dig, code, comm, timings) -> ReducedModel:
    from .interface import interface_points
    from .mesh import read_msh
    from .rigid import mass_properties, rigid_matrices

    with stage(timings, "read_mesh"):
        fm = read_msh(geom.damper_msh, comm)
    with stage(timings, "mass_properties"):
        rho = float(geom.material["rho_kg_m3"])
        m, c, J = mass_properties(fm, rho)
        n_nodes_global = fm.mesh.geometry.index_map().size_global
    pts, sets, _ = interface_points(geom, "damper")
    K, M, T = rigid_matrices(m, J, c, pts)
    info(
        log,
        comm,
        "damper (rigid): mass %.4g kg (record %.4g kg), centroid %s m",
        m,
        geom.damper_mass_kg,
        np.array2string(c, precision=5),
    )
    return ReducedModel(
        name="damper",
        kind="rigid",
        K=K,
        M=M,
        T=T,
        node_coords=pts,
        node_sets=sets,
        ref_point=c,
        inputs=inputs,
        digest=dig,
        code_version=code,
        n_full_dofs=3 * int(n_nodes_global),
    )


def _craig_bampton(geom, body, n_modes, inputs, dig, code, comm, timings) -> ReducedModel:
    import scipy.linalg as sl

    from .craig_bampton import craig_bampton
    from .interface import interface_points, locate_nodes
    from .modes import load_bodies

    eb = load_bodies(geom, comm, timings, which=(body,))[body]
    pts, sets, labels = interface_points(geom, body)
    with stage(timings, "locate"):
        nodes = locate_nodes(eb, pts, labels=labels)
    pad = float(geom.params.get("rig", {}).get("mesh", {}).get("pad_mm", 0.0)) * 1e-3
    if pad > 0:
        from .pads import tie_pads

        with stage(timings, "pads"):
            counts = tie_pads(eb, nodes, geom.contact, pad)
        info(log, comm, "%s: %d nodes tied to the contact points' pads (%.1f per pair)",
             body, counts["pad_nodes"], counts["pad_nodes_per_pair"])  # fmt: skip
    cb = craig_bampton(eb, nodes, n_modes, timings=timings)
    nb = cb.n_b
    T = np.zeros((nb, cb.K.shape[0]))
    T[:, :nb] = np.eye(nb)
    rm = ReducedModel(
        name=body,
        kind="craig-bampton",
        K=cb.K,
        M=cb.M,
        T=T,
        node_coords=pts,
        node_sets=sets,
        mode_freqs_hz=cb.mode_freqs_hz,
        inputs=inputs,
        digest=dig,
        code_version=code,
        n_full_dofs=eb.n_dofs,
    )
    with stage(timings, "check"):
        lam = sl.eigh(rm.K, rm.M, eigvals_only=True)
    if body == "damper":
        scale = lam[6] if len(lam) > 6 else 1.0
        n_rigid = int(np.sum(np.abs(lam) < RIGID_RATIO * scale))
        if n_rigid != 6 or scale <= 0:
            raise SolveError(
                f"damper: the reduced free-free damper has {n_rigid} zero eigenvalues instead of 6",
                partial=rm,
            )
        info(
            log,
            comm,
            "damper: reduced free-free model has 6 rigid-body modes "
            "(|lambda| <= %.1e of the first elastic), first elastic %.0f Hz",
            np.abs(lam[:6]).max() / scale,
            np.sqrt(scale) / (2 * np.pi),
        )
    elif lam[0] <= 0:
        raise SolveError(
            f"rig: the reduced clamped rig is not positive definite "
            f"(lowest eigenvalue {lam[0]:.3e})",
            partial=rm,
        )
    return rm

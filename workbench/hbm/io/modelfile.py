"""The TOML input of ``upd frf``: reduced matrices from any FE code, excitation, contacts.

A model file (every key is checked; unknown keys are refused with a hint)::

    [model]
    matrices = "model.npz"      # relative to this file: .npz, .h5, or an FE code's
                                # export (.op4, .pch, .mtx, .mm, .rua/.rsa): see below
    mass = "M"                  # array (dataset, matrix) names in that file
    stiffness = "K"
    damping = ""                # a viscous matrix C (N s/m); empty: damping_ratio
    damping_ratio = 0.005       # modal damping on the modes with stuck contacts
    static_force = ""           # an optional constant force vector (N)
    balance = true              # add the force that carries the contact preloads
    length_unit = "m"           # unit of the DOFs (peak_amplitude is in this unit)
    dof_map = ""                # node/component of each row, for formats without labels

    [excitation]                # f(t) = level * amplitude * cos(w t + phase)
    dofs = [0]
    amplitudes_n = [1.0]        # N per unit level
    phases_deg = [0.0]
    levels = [0.5, 1.0, 2.0]

    [band]
    start_hz = 80.0
    end_hz = 150.0

    [hbm]
    harmonics = [0, 1, 2, 3]
    nt = 0                      # samples per period; 0 picks one

    [output]
    dofs = [0]
    names = ["x"]

    [[contact]]                 # one table per group of elements with the same parameters
    dofs = [[0, -1, 1]]         # per element [t1] or [t1, t2, n] (-1: no such direction)
    other = []                  # platform DOFs (same shape); empty: against the ground
    mu = 0.3
    kt_n_per_m = 1.0e5
    kn_n_per_m = 2.0e5
    n0_n = 5.0
    law = "decoupled"           # and the law's own parameters (its PARAMS) if it has any

    [solver]                    # any field of workbench.hbm.SolverOptions
    ds_max = 0.2

Matrices in a ``.npz`` are arrays; a sparse matrix ``K`` may be stored as
``K_data``, ``K_indices``, ``K_indptr``, ``K_shape`` (CSR). In HDF5 they
are datasets (or groups with those four members).

Matrices from an FE code (``workbench.readers``): ``matrices`` may be a
Nastran OP4 or DMIG punch file (``mass = "MAAX"`` names a matrix in it).
With ``matrices = ""`` each of ``mass``, ``stiffness``, ``damping`` is a
file of its own, optionally ``"file#NAME"`` (Abaqus ``job_MASS2.mtx``,
Matrix Market, Harwell-Boeing). DMIG and Abaqus files label every row with
a (node id, component 1-6); for the others ``dof_map`` gives the labels.
With labels, contacts, excitation and outputs can name nodes instead of
DOF indices::

    [excitation]
    dofs = [[101, 2]]           # [node id, component] pairs or DOF indices

    [[contact]]
    nodes = [101, 102]          # one element per node (damper side)
    other_nodes = [201, 202]    # the facing platform nodes; empty: the ground
    components = [1, 2, 3]      # node components for t1, t2, n (-1: none)
"""

from __future__ import annotations

import dataclasses
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ...config import load_record, param, read_toml
from ...contact import LAWS, ContactElements
from ...errors import InputError, WorkbenchError, check_int, check_range, did_you_mean
from ...limits import (
    ENTRY_MAX,
    ENTRY_WHY,
    FRF_BAND_RATIO_MAX,
    FRF_BAND_WHY,
    MAX_HARMONIC,
    MAX_NT,
    MU_MAX,
    MU_WHY,
    NT_WHY,
)
from ...matrix_checks import csr_from_parts
from ..core.options import SolverOptions
from ..core.system import System
from . import modelcheck


@dataclass(frozen=True)
class ModelSection:
    matrices: str = param("", "file with the matrices (.npz or .h5), relative to the TOML file")
    mass: str = param("M", "name of the mass matrix (kg)")
    stiffness: str = param("K", "name of the stiffness matrix (N/m)")
    damping: str = param("", "name of a viscous damping matrix (N s/m); empty: damping_ratio")
    damping_ratio: float = param(
        0.0, "modal damping ratio on the modes with stuck contacts", lo=0.0, hi=1.0
    )
    static_force: str = param("", "name of a constant force vector (N); empty: none")
    balance: bool = param(True, "add the constant force that carries the contact preloads")
    length_unit: str = param("m", "unit of the generalised displacements")
    dof_map: str = param(
        "", "text file with the (node, component) of each row, for OP4/Matrix Market/HB"
    )


@dataclass(frozen=True)
class ExcitationSection:
    dofs: list = param([], "DOFs loaded by the harmonic force")
    amplitudes_n: list = param([], "force amplitude per DOF per unit level, N")
    phases_deg: list = param([], "phase per DOF, deg (default 0)")
    levels: list = param([1.0], "excitation levels (multipliers of the amplitudes)")


@dataclass(frozen=True)
class BandSection:
    start_hz: float = param(float("nan"), "band start, Hz")
    end_hz: float = param(float("nan"), "band end, Hz")


@dataclass(frozen=True)
class HbmSection:
    harmonics: list = param([0, 1, 2, 3], "harmonic list (must include 1)")
    nt: int = param(0, "time samples per period (0: automatic)", lo=0, hi=MAX_NT, why=NT_WHY)


@dataclass(frozen=True)
class OutputSection:
    dofs: list = param([], "output DOFs")
    names: list = param([], "output names (default y0, y1, ...)")


@dataclass(frozen=True)
class ContactSection:
    dofs: list = param([], "per element [t1] or [t1, t2, n] DOFs (-1: no such direction)")
    other: list = param([], "platform DOFs per element (same shape); empty: against the ground")
    frames: list = param([], "per element 3x3 rows t1, t2, n when dofs are the node's x, y, z")
    nodes: list = param([], "node ids of the elements (instead of dofs; needs node labels)")
    other_nodes: list = param([], "facing node id per element (instead of other)")
    components: list = param([1, 2, 3], "node components (1-6) for t1, t2, n; -1: none")
    mu: float = param(0.5, "friction coefficient", lo=0.0, hi=MU_MAX, why=MU_WHY)
    kt_n_per_m: float = param(0.0, "tangential stiffness, N/m", lo=0.0, hi=ENTRY_MAX, why=ENTRY_WHY)
    kt2_n_per_m: float = param(
        -1.0,
        "second tangential stiffness, N/m (default: kt_n_per_m)",
        hi=ENTRY_MAX,
        why=ENTRY_WHY,
    )
    kn_n_per_m: float = param(0.0, "normal stiffness, N/m", lo=0.0, hi=ENTRY_MAX, why=ENTRY_WHY)
    n0_n: float = param(
        0.0, "normal preload, N (compressive positive)", lo=0.0, hi=ENTRY_MAX, why=ENTRY_WHY
    )
    law: str = param("decoupled", "friction law", choices=LAWS)


_SECTIONS = {
    "model": ModelSection,
    "excitation": ExcitationSection,
    "band": BandSection,
    "hbm": HbmSection,
    "output": OutputSection,
    "contact": ContactSection,
    "solver": SolverOptions,
}


@dataclass
class FrfModel:
    """Everything ``upd frf`` needs, read from a model file."""

    system: System
    f1: np.ndarray  # (n,) complex, N per unit level
    levels: tuple[float, ...]
    band_hz: tuple[float, float]
    harmonics: tuple[int, ...]
    nt: int
    outputs: np.ndarray  # DOF indices
    output_names: tuple[str, ...]
    options: SolverOptions
    length_unit: str
    path: Path
    name: str
    raw: dict[str, Any] = field(default_factory=dict)


def _read_arrays(path: Path) -> dict[str, Any]:
    from ...readers import NUMPY_SUFFIXES, _read_numpy

    if path.suffix not in NUMPY_SUFFIXES:
        raise InputError("model.matrices", str(path), "a .npz or .h5/.hdf5 file")
    return _read_numpy(path)


def _matrix(arrays: dict[str, Any], name: str, key: str, file: Path):
    if name in arrays:
        return arrays[name]
    parts = [f"{name}{s}" for s in ("_data", "_indices", "_indptr", "_shape")]
    parts_h5 = [f"{name}/{s}" for s in ("data", "indices", "indptr", "shape")]
    for p in (parts, parts_h5):
        if all(q in arrays for q in p):  # each part checked: a bad index would crash SciPy
            return csr_from_parts(arrays[p[0]], arrays[p[1]], arrays[p[2]], arrays[p[3]], key)
    names = sorted(
        {
            k.split("/")[0].rsplit("_", 1)[0]
            if k.endswith(("_data", "_indices", "_indptr", "_shape"))
            else k
            for k in arrays
        }
    )
    raise InputError(
        key,
        name,
        f"one of the arrays in {file.name}: {', '.join(names)}",
        did_you_mean(name, names),
    )


def _read_model_matrices(m: ModelSection, path: Path):
    """M, K, C, static force and the row labels (or None) of the [model] section."""
    from ... import readers

    roles = {"mass": m.mass, "stiffness": m.stiffness}
    if m.damping:
        roles["damping"] = m.damping
    dof_map = (path.parent / m.dof_map).resolve() if m.dof_map else None
    if dof_map is not None and not dof_map.is_file():
        raise InputError("model.dof_map", m.dof_map, f"an existing file (looked in {path.parent})")
    if not m.matrices:
        specs = {}
        for role, spec in roles.items():
            fname, hash_, name = str(spec).partition("#")
            f = (path.parent / fname).resolve()
            if not f.is_file():
                raise InputError(
                    f"model.{role}",
                    spec,
                    "a matrix file (model.matrices is empty), looked in " + str(path.parent),
                )
            specs[role] = f"{f}{hash_}{name}"
        if m.static_force:
            raise InputError(
                "model.static_force",
                m.static_force,
                "empty when model.matrices is empty (a vector needs a .npz/.h5)",
            )
        ms = readers.read_matrices(specs, dof_map)
        M, K = ms.matrices["mass"], ms.matrices["stiffness"]
        return M, K, ms.matrices.get("damping"), None, ms
    mfile = (path.parent / m.matrices).resolve()
    if not mfile.is_file():
        raise InputError(
            "model.matrices", m.matrices, f"an existing file (looked in {path.parent})"
        )
    if readers.file_kind(mfile) != "numpy":
        if m.static_force:
            raise InputError(
                "model.static_force",
                m.static_force,
                "empty for an FE export (a vector needs a .npz/.h5)",
            )
        ms = readers.read_matrices(
            {r: f"{mfile}#{v}" for r, v in roles.items()}, dof_map, "model.matrices"
        )
        M, K = ms.matrices["mass"], ms.matrices["stiffness"]
        return M, K, ms.matrices.get("damping"), None, ms
    try:
        arrays = _read_arrays(mfile)
    except WorkbenchError:
        raise
    except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile) as e:
        # numpy/h5py on a truncated or corrupt .npz/.h5
        raise InputError(
            "model.matrices",
            m.matrices,
            "a readable .npz or HDF5 file",
            f"{type(e).__name__}: {str(e)[:160]}",
        ) from None
    M = _matrix(arrays, m.mass, "model.mass", mfile)
    K = _matrix(arrays, m.stiffness, "model.stiffness", mfile)
    C = _matrix(arrays, m.damping, "model.damping", mfile) if m.damping else None
    fs = None
    if m.static_force:
        fs = _matrix(arrays, m.static_force, "model.static_force", mfile)
    labels = readers.read_dof_map(dof_map) if dof_map else None
    if labels is not None and len(labels) != np.shape(M)[0]:
        raise InputError(
            "model.dof_map", m.dof_map, f"{M.shape[0]} rows (one per DOF)", f"it has {len(labels)}"
        )
    ms = readers.MatrixSet({"mass": M}, labels, mfile.name)
    return M, K, C, fs, ms


def _resolve_nodes(key: str, value: Any, ms) -> Any:
    """Replace ``[node, component]`` entries of a DOF list by row indices."""
    if not isinstance(value, list):
        return value
    from ...readers import component_number

    out = []
    for i, v in enumerate(value):
        if isinstance(v, list):
            if len(v) != 2:
                raise InputError(f"{key}[{i}]", v, "a DOF index or a [node id, component] pair")
            out.append(ms.index(v[0], component_number(v[1], f"{key}[{i}]"), f"{key}[{i}]"))
        else:
            out.append(v)
    return out


def _contact_by_node(g: ContactSection, ms, where: str) -> ContactSection:
    """The same section with ``dofs``/``other`` filled from node ids and components."""
    from ...readers import component_number

    if g.dofs or g.other:
        raise InputError(f"{where}.dofs", g.dofs, "empty when nodes are given (one or the other)")
    comps = g.components
    if not isinstance(comps, list) or not 1 <= len(comps) <= 3:
        raise InputError(f"{where}.components", comps, "1 to 3 components for t1, t2, n")
    comps = [-1 if c == -1 else component_number(c, f"{where}.components") for c in comps]
    if g.other_nodes and len(g.other_nodes) != len(g.nodes):
        raise InputError(
            f"{where}.other_nodes",
            g.other_nodes,
            f"{len(g.nodes)} node ids (one per element) or empty",
        )

    def row(node, k):
        return [-1 if c == -1 else ms.index(node, c, f"{where}.{k}") for c in comps]

    for k in ("nodes", "other_nodes"):
        for j, v in enumerate(getattr(g, k)):
            if isinstance(v, bool) or not isinstance(v, int):
                raise InputError(f"{where}.{k}[{j}]", v, "a node id (whole number)")
    dofs = [row(v, "nodes") for v in g.nodes]
    other = [row(v, "other_nodes") for v in g.other_nodes]
    return dataclasses.replace(g, dofs=dofs, other=other)


def _int_list(key: str, value: Any, n: int, allow_none: bool = False) -> list[int]:
    if not isinstance(value, list) or not all(
        isinstance(v, int) and not isinstance(v, bool) for v in value
    ):
        raise InputError(key, value, "a list of whole numbers (DOF indices)")
    lo = -1 if allow_none else 0
    if n < 1:  # no DOF at all: the matrices are empty, not the index wrong
        raise InputError("model.mass", "shape (0, 0)", "a square matrix, 1 x 1 or more")
    for i, v in enumerate(value):
        if not lo <= v < n:
            raise InputError(f"{key}[{i}]", v, f"a DOF index {lo} <= i < {n}")
    return list(value)


def _float_list(
    key: str,
    value: Any,
    lo: float | None = None,
    lo_open: bool = False,
    hi: float | None = None,
) -> list[float]:
    if not isinstance(value, list):
        raise InputError(key, value, "a list of numbers")
    return [check_range(f"{key}[{i}]", v, lo, hi, lo_open=lo_open) for i, v in enumerate(value)]


def _sections(data: dict[str, Any], complete: bool = True) -> tuple[dict, list]:
    """The checked records of a model file's tables (``complete``: the required keys too)."""
    for key in data:
        if key not in _SECTIONS:
            raise InputError(
                key,
                "[...]",
                "one of the sections " + ", ".join(_SECTIONS),
                ("unknown section; " + did_you_mean(key, _SECTIONS)).rstrip("; "),
            )
    band = data.get("band", {})
    for key in ("start_hz", "end_hz"):
        if complete and (not isinstance(band, dict) or key not in band):
            raise InputError(f"band.{key}", "missing", "a frequency > 0 Hz in the table [band]")
    sec = {}
    for key, cls in _SECTIONS.items():
        if key == "contact":
            continue
        tab = data.get(key, {})
        if not isinstance(tab, dict):
            raise InputError(key, tab, f"a table [{key}]")
        sec[key] = load_record(cls, tab, f"{key}.")
    modelcheck.check_solver(sec["solver"])
    groups = data.get("contact", [])
    if isinstance(groups, dict):
        groups = [groups]
    if not isinstance(groups, list):
        raise InputError("contact", groups, "tables [[contact]]")
    # (record, the law's own parameters) per table
    contact = [modelcheck.contact_group(ContactSection, g, i) for i, g in enumerate(groups)]
    e: ExcitationSection = sec["excitation"]
    _float_list("excitation.amplitudes_n", e.amplitudes_n, -ENTRY_MAX, hi=ENTRY_MAX)
    _float_list("excitation.phases_deg", e.phases_deg, -360.0, hi=360.0)
    _float_list("excitation.levels", e.levels, 0.0, lo_open=True, hi=ENTRY_MAX)
    b: BandSection = sec["band"]
    if complete or "start_hz" in band:
        lo = check_range("band.start_hz", b.start_hz, 0.0, lo_open=True, unit="Hz")
        if complete or "end_hz" in band:
            hi = check_range("band.end_hz", b.end_hz, lo, lo_open=True, unit="Hz")
            if hi / lo > FRF_BAND_RATIO_MAX:
                raise InputError(
                    "band",
                    [lo, hi],
                    f"end_hz / start_hz <= {FRF_BAND_RATIO_MAX:g} (it is {hi / lo:.3g})",
                    FRF_BAND_WHY,
                )
    h: HbmSection = sec["hbm"]
    if not isinstance(h.harmonics, list):
        raise InputError("hbm.harmonics", h.harmonics, "a list of whole numbers")
    for i, k in enumerate(h.harmonics):
        if isinstance(k, float):  # 1.0 in a list of harmonics is a typo, not a harmonic
            raise InputError(f"hbm.harmonics[{i}]", k, "a whole number (no decimal point)")
        check_int(f"hbm.harmonics[{i}]", k, 0, MAX_HARMONIC)
    if h.nt and h.harmonics and h.nt <= 2 * max(h.harmonics):
        raise InputError(
            "hbm.nt",
            h.nt,
            f"hbm.nt > 2 x the highest harmonic = {2 * max(h.harmonics)}",
            "the sampling theorem; 0 picks one",
        )
    return sec, contact


def load_frf_model(
    path: str | Path,
    overrides: dict[str, Any] | None = None,
    names: dict[str, str] | None = None,
) -> FrfModel:
    """Read and check a model file; ``overrides`` replaces keys (``{"band": {...}}``).

    The file's own values are checked first, also those that ``overrides``
    replaces (a typo in the file does not hide behind a command-line value).
    ``names``: how the errors call an overridden key (``{"band": "--band"}``).
    """
    path = Path(path)
    data = read_toml(path)
    if not data:
        raise InputError(
            "file",
            str(path),
            "a model file with the tables [model], [excitation], [band], [output]",
            "it is empty",
        )
    if overrides:
        try:
            _sections(data, complete=False)
        except InputError as e:
            why = (e.why + "; " if e.why else "") + (
                f"in {path.name}, checked although the command line overrides it"
            )
            raise InputError(e.param, e.value, e.allowed, why) from None
    for key, val in (overrides or {}).items():
        data.setdefault(key, {})
        data[key].update(val)
    try:
        return _build(path, data)
    except InputError as e:
        for key, flag in (names or {}).items():
            sect, _, k = key.partition(".")
            given = sect in (overrides or {}) and (not k or k in overrides[sect])
            rest = e.param[len(key) :]
            if given and e.param.startswith(key) and rest[:1] in ("", "[", "."):
                index = rest if rest.startswith("[") else ""
                raise InputError(flag + index, e.value, e.allowed, e.why) from None
        raise


def _build(path: Path, data: dict[str, Any]) -> FrfModel:
    sec, contact = _sections(data)
    m: ModelSection = sec["model"]
    M, K, C, fs, labels = _read_model_matrices(m, path)
    M, K, C, fs = modelcheck.check_matrices(M, K, C, fs, labels)
    n = M.shape[0]

    parts, groups = [], []
    for i, (g, own) in enumerate(contact):
        where = f"contact[{i}]"
        if g.nodes:
            g = _contact_by_node(g, labels, where)
        if not g.dofs:
            raise InputError(f"{where}.dofs", [], "DOFs of at least one element")
        dofs = g.dofs if isinstance(g.dofs[0], list) else [g.dofs]
        flat = [d for el in dofs for d in (el if isinstance(el, list) else [el])]
        _int_list(f"{where}.dofs", flat, n, allow_none=True)
        other = None
        if g.other:
            other = g.other if isinstance(g.other[0], list) else [g.other]
            if not all(isinstance(el, list) for el in other):
                raise InputError(f"{where}.other", g.other, "one list of DOFs per element")
            _int_list(f"{where}.other", [d for el in other for d in el], n, allow_none=True)
        frames = modelcheck.frames(f"{where}.frames", g.frames) if g.frames else None
        if g.kt_n_per_m <= 0 and any(len(el) >= 1 and el[0] >= 0 for el in dofs):
            raise InputError(f"{where}.kt_n_per_m", g.kt_n_per_m, "a tangential stiffness > 0 N/m")
        kt2 = g.kt_n_per_m if g.kt2_n_per_m < 0 else g.kt2_n_per_m
        try:
            part = ContactElements.from_dofs(
                n,
                dofs,
                other=other,
                frames=frames,
                mu=g.mu,
                kt=g.kt_n_per_m,
                kt2=kt2,
                kn=g.kn_n_per_m,
                n0=g.n0_n,
                law=g.law,
                law_params=own,
            )
        except InputError as e:  # name the group: "dofs[1]" -> "contact[0].dofs[1]"
            raise InputError(f"{where}.{e.param}", e.value, e.allowed, e.why) from None
        modelcheck.check_contact_group(where, part, dofs, frames, K)
        parts.append(part)
        groups.append((where, part))
    elements = ContactElements.concat(parts) if parts else None

    e: ExcitationSection = sec["excitation"]
    dofs = _int_list("excitation.dofs", _resolve_nodes("excitation.dofs", e.dofs, labels), n)
    if not dofs:
        raise InputError("excitation.dofs", [], "at least one loaded DOF")
    amps = _float_list("excitation.amplitudes_n", e.amplitudes_n)
    if len(amps) != len(dofs):
        raise InputError(
            "excitation.amplitudes_n", e.amplitudes_n, f"{len(dofs)} values (one per DOF)"
        )
    phases = (
        _float_list("excitation.phases_deg", e.phases_deg) if e.phases_deg else [0.0] * len(dofs)
    )
    if len(phases) != len(dofs):
        raise InputError("excitation.phases_deg", e.phases_deg, f"{len(dofs)} values (one per DOF)")
    levels = _float_list("excitation.levels", e.levels, 0.0, lo_open=True)
    if not levels:
        raise InputError("excitation.levels", [], "at least one level > 0")
    f1 = np.zeros(n, complex)
    for d, a, ph in zip(dofs, amps, phases, strict=True):
        f1[d] += a * np.exp(1j * np.radians(ph))
    modelcheck.check_levels("excitation.levels", levels, f1, groups)

    b: BandSection = sec["band"]
    lo, hi = float(b.start_hz), float(b.end_hz)

    h: HbmSection = sec["hbm"]
    harm = list(h.harmonics)
    o: OutputSection = sec["output"]
    outs = _int_list("output.dofs", _resolve_nodes("output.dofs", o.dofs, labels), n)
    if not outs:
        raise InputError("output.dofs", [], "at least one output DOF")
    names = tuple(str(v) for v in o.names) if o.names else tuple(f"dof{d}" for d in outs)
    if len(names) != len(outs):
        raise InputError("output.names", o.names, f"{len(outs)} names (one per output DOF)")
    modelcheck.check_stiffness(M, K, elements, groups)
    modelcheck.check_size(
        tuple(harm),
        h.nt,
        n,
        elements.n_el if elements else 0,
        "hbm.nt" if h.nt else "hbm.harmonics",
    )

    system = System(
        M=M,
        K=K,
        C=C,
        zeta=None if C is not None else m.damping_ratio,
        contacts=elements,
        static_force=fs,
        balance=m.balance,
    )
    return FrfModel(
        system=system,
        f1=f1,
        levels=tuple(levels),
        band_hz=(lo, hi),
        harmonics=tuple(harm),
        nt=h.nt,
        outputs=np.array(outs),
        output_names=names,
        options=sec["solver"],
        length_unit=m.length_unit,
        path=path,
        name=path.stem,
        raw={k: dataclasses.asdict(v) for k, v in sec.items()},
    )

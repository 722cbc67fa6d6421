"""Readers for reduced matrices exported by the FE codes damper engineers use.

One entry point, :func:`read_matrices`, returns a :class:`MatrixSet`: the
matrices by name and, when the file says so, the label of every row as a
``(node id, component)`` pair (components 1-6: x, y, z, rx, ry, rz in the
node's output frame). The labels let a model file name contact pairs by
node id instead of DOF indices (``workbench.hbm.io.modelfile``).

=====================================  ==========================  ==========
format (suffix)                        read with                   labels
=====================================  ==========================  ==========
Nastran OUTPUT4 ``.op4`` (text/binary)  pyNastran ``read_op4``      dof_map
Nastran DMIG punch ``.pch`` ``.dmig``   pyNastran ``read_bdf``      in file
Abaqus ``*MATRIX GENERATE`` ``.mtx``    this module (plain text)    in file
Matrix Market ``.mtx`` ``.mm``          ``scipy.io.mmread``         dof_map
Harwell-Boeing ``.rua`` ``.rsa`` ...    ``scipy.io.hb_read``        dof_map
numpy ``.npz``, HDF5 ``.h5``            numpy / h5py                none
=====================================  ==========================  ==========

A ``.mtx`` is Matrix Market when its first line starts with
``%%MatrixMarket`` and Abaqus otherwise. Abaqus writes a symmetric matrix as
one triangle (``FORMAT=MATRIX INPUT``: ``row node, row dof, column node,
column dof, value``); the other triangle is filled in. ANSYS users export
the ``.full`` file with ``HBMAT`` (Harwell-Boeing, symmetric ``RSA`` files
hold the lower triangle, which is mirrored here) and give its ``.mapping``
file as the DOF map. A DOF map (:func:`read_dof_map`) is a text file with one
row per matrix row: ``node component`` or ``equation node component``;
components may be numbers or ANSYS names (UX ... ROTZ); header lines are
skipped.
"""

from __future__ import annotations

import functools
import io
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp

from .errors import InputError, WorkbenchError, did_you_mean
from .matrix_checks import check_matrix

Label = tuple[int, int]

_COMPONENT_NAMES = {
    "UX": 1,
    "UY": 2,
    "UZ": 3,
    "ROTX": 4,
    "ROTY": 5,
    "ROTZ": 6,
    "RX": 4,
    "RY": 5,
    "RZ": 6,
    "X": 1,
    "Y": 2,
    "Z": 3,
}
OP4_SUFFIXES = (".op4",)
DMIG_SUFFIXES = (".pch", ".dmig", ".bdf", ".dat", ".blk")
HB_SUFFIXES = (".rua", ".rsa", ".rb", ".hb", ".hbf")
MM_SUFFIXES = (".mm",)
MTX_SUFFIXES = (".mtx",)
NUMPY_SUFFIXES = (".npz", ".h5", ".hdf5")
SUFFIXES = OP4_SUFFIXES + DMIG_SUFFIXES + HB_SUFFIXES + MM_SUFFIXES + MTX_SUFFIXES + NUMPY_SUFFIXES


@dataclass(frozen=True)
class MatrixSet:
    """Matrices read from one or more files, on one common row numbering.

    ``labels[i]`` is the ``(node id, component)`` of row ``i``, or ``labels``
    is None when the format carries none and no DOF map was given.
    """

    matrices: dict[str, Any]
    labels: tuple[Label, ...] | None
    source: str

    @property
    def n(self) -> int:
        return next(iter(self.matrices.values())).shape[0]

    def index(self, node: int, component: int, param: str = "node") -> int:
        """The row index of ``(node, component)``; InputError naming ``param`` if absent."""
        if self.labels is None:
            raise InputError(
                param,
                [node, component],
                "DOF indices (the matrix file has no node labels; give model.dof_map)",
            )
        lookup = self._lookup
        try:
            return lookup[(int(node), int(component))]
        except KeyError:
            nodes = sorted({n for n, _ in self.labels})
            comps = sorted(c for n, c in self.labels if n == node)
            allowed = (
                f"a component of node {node} in {self.source}: {comps}"
                if comps
                else f"a node of {self.source} ({len(nodes)} nodes, {nodes[0]}..{nodes[-1]})"
            )
            raise InputError(param, [node, component], allowed) from None

    @functools.cached_property
    def _lookup(self) -> dict[Label, int]:
        """(node, component) -> row, built on first use (cached_property: no field is set)."""
        return {lab: i for i, lab in enumerate(self.labels or ())}


_COMPONENTS_ALLOWED = "a component 1-6 or one of UX UY UZ ROTX ROTY ROTZ"


def component_number(value: Any, param: str = "component") -> int:
    """1-6 from a number or a name (UX, UY, UZ, ROTX, ROTY, ROTZ; x, y, z)."""
    if isinstance(value, str) and value.strip().upper() in _COMPONENT_NAMES:
        return _COMPONENT_NAMES[value.strip().upper()]
    try:
        c = int(value)
    except (TypeError, ValueError):
        raise InputError(param, value, _COMPONENTS_ALLOWED) from None
    if not 1 <= c <= 6 or isinstance(value, bool) or float(value) != c:
        raise InputError(param, value, _COMPONENTS_ALLOWED)
    return c


# -- DOF map ------------------------------------------------------------------------------


def read_dof_map(path: str | Path) -> tuple[Label, ...]:
    """Row labels from a text file: ``node comp`` or ``eqn node comp`` per line.

    Lines that do not start with a number (headers, ``#`` comments) are
    skipped; with three columns the first (equation number, 1-based) must
    count 1, 2, 3, ... so that the rows are in matrix order.
    """
    path = Path(path)
    out: list[Label] = []
    for k, line in enumerate(_text(path, "model.dof_map", "a text DOF map").splitlines(), 1):
        parts = line.replace(",", " ").split()
        if not parts or not parts[0].lstrip("-").isdigit():
            continue
        where = f"dof_map {path.name} line {k}"
        if len(parts) == 3:
            if int(parts[0]) != len(out) + 1:
                raise InputError(where, line.strip(), f"equation number {len(out) + 1}")
            parts = parts[1:]
        if len(parts) != 2:
            raise InputError(where, line.strip(), "'node component' or 'equation node component'")
        out.append((int(parts[0]), component_number(parts[1], where)))
    if not out:
        raise InputError("model.dof_map", str(path), "a file with one 'node component' row per DOF")
    if len(set(out)) != len(out):
        dup = next(lab for lab in out if out.count(lab) > 1)
        raise InputError("model.dof_map", str(path), "each (node, component) once", f"{dup} twice")
    return tuple(out)


# -- single formats -----------------------------------------------------------------------


def read_op4(
    path: str | Path, names: list[str] | None = None, param: str = "model.matrices"
) -> dict[str, Any]:
    """Matrices of a Nastran OUTPUT4 file (text or binary) by name (pyNastran)."""
    from pyNastran.op4.op4 import read_op4 as _read

    try:
        mats = _read(str(path), matrix_names=names, debug=False, log=_quiet_log())
    except Exception as e:  # pyNastran raises bare exceptions on malformed files
        raise InputError(param, str(path), "a readable Nastran OP4 file", str(e)) from None
    return {name: _as_matrix(m.data, f"{param} {name}") for name, m in mats.items()}


def read_dmig(
    path: str | Path, param: str = "model.matrices"
) -> tuple[dict[str, Any], tuple[Label, ...]]:
    """DMIG matrices of a Nastran punch/bulk file on the union of their (grid, component)."""
    from pyNastran.bdf.bdf import read_bdf

    try:
        model = read_bdf(str(path), punch=True, xref=False, debug=None, log=_quiet_log())
    except Exception as e:
        raise InputError(param, str(path), "a Nastran punch file with DMIG cards", str(e)) from None
    if not model.dmig:
        raise InputError(
            param,
            str(path),
            "a Nastran punch file with DMIG cards",
            "no DMIG card found",
        )
    parts: dict[str, tuple[Any, list[Label], list[Label]]] = {}
    for name, card in model.dmig.items():
        if not hasattr(card, "get_matrix"):
            continue  # DMIG,UACCEL is a load, not a matrix
        a, rows, cols = card.get_matrix(is_sparse=False, apply_symmetry=True)
        rl = [tuple(int(v) for v in rows[i]) for i in range(len(rows))]
        cl = [tuple(int(v) for v in cols[i]) for i in range(len(cols))]
        parts[name] = (check_matrix(a, f"{param} {name}", square=False), rl, cl)
    labels = tuple(sorted({lab for _, r, c in parts.values() for lab in (*r, *c)}))
    index = {lab: i for i, lab in enumerate(labels)}
    out = {}
    for name, (a, rl, cl) in parts.items():
        ri = np.array([index[lab] for lab in rl])
        ci = np.array([index[lab] for lab in cl])
        full = np.zeros((len(labels), len(labels)))
        full[np.ix_(ri, ci)] = a
        out[name] = sp.csr_matrix(full)
    return out, labels


def read_abaqus_mtx(
    path: str | Path, param: str = "model.matrices"
) -> tuple[Any, tuple[Label, ...]]:
    """An Abaqus ``*MATRIX GENERATE`` file (``FORMAT=MATRIX INPUT``).

    Each data line is ``row node, row dof, column node, column dof, value``;
    lines starting with ``*`` are comments or keywords. Rows are numbered by
    (node, dof) in ascending order. A symmetric matrix given as one triangle
    is completed; a square one is kept as is; a mix is refused.
    """
    path = Path(path)
    ri, rc, ci, cc, vals = [], [], [], [], []
    for k, line in enumerate(_text(path, param, "an Abaqus .mtx text file").splitlines(), 1):
        s = line.strip()
        if not s or s.startswith("*"):
            continue
        parts = s.replace(",", " ").split()
        if len(parts) != 5:
            raise InputError(
                f"{path.name} line {k}",
                s,
                "'row node, row dof, column node, column dof, value' (Abaqus MATRIX INPUT)",
            )
        try:
            a, b, c, d = (int(p) for p in parts[:4])
            v = float(parts[4].replace("D", "E").replace("d", "e"))
        except ValueError:
            raise InputError(f"{path.name} line {k}", s, "four whole numbers and a value") from None
        ri.append(a), rc.append(b), ci.append(c), cc.append(d), vals.append(v)
    if not vals:
        raise InputError(param, str(path), "an Abaqus .mtx file with matrix entries")
    labels = tuple(sorted(set(zip(ri, rc, strict=True)) | set(zip(ci, cc, strict=True))))
    index = {lab: i for i, lab in enumerate(labels)}
    r = np.array([index[q] for q in zip(ri, rc, strict=True)])
    c = np.array([index[q] for q in zip(ci, cc, strict=True)])
    v = np.array(vals)
    return _complete_symmetric(r, c, v, len(labels), path, param), labels


def _complete_symmetric(r, c, v, n, path, param="model.matrices") -> sp.csr_matrix:
    off = r != c
    pairs = set(zip(r[off].tolist(), c[off].tolist(), strict=True))
    mirrored = sum((j, i) in pairs for i, j in pairs)
    if mirrored == 0:  # one triangle: fill in the other
        r, c = np.concatenate([r, c[off]]), np.concatenate([c, r[off]])
        v = np.concatenate([v, v[off]])
    elif mirrored != len(pairs):
        raise InputError(
            param,
            str(path),
            "one triangle of a symmetric matrix or the full square matrix",
            f"{mirrored} of {len(pairs)} off-diagonal entries have their mirror",
        )
    m = sp.coo_matrix((v, (r, c)), shape=(n, n)).tocsr()
    m.sum_duplicates()
    return m


_MM_ALLOWED = (
    "a Matrix Market matrix file: '%%MatrixMarket matrix coordinate|array "
    "real|double|integer general|symmetric'"
)


def read_matrix_market(path: str | Path, param: str = "model.matrices") -> Any:
    """A Matrix Market file (``scipy.io.mmread``), as CSR or dense.

    The header is checked first: a ``pattern`` file (no values), a
    ``skew-symmetric`` or ``vector`` one, or an unknown word is refused, and
    so is an entry given twice (summed silently otherwise).
    """
    import scipy.io

    path = Path(path)
    with path.open("rb") as fh:
        head = fh.readline(200).decode("ascii", "backslashreplace").split()
    words = [w.lower() for w in head]
    if len(words) != 5 or words[0] != "%%matrixmarket" or words[1] != "matrix":
        raise InputError(param, str(path), _MM_ALLOWED, f"its first line is {' '.join(head)!r}")
    fmt, field, sym = words[2:]
    why = {
        "pattern": "a pattern file holds no values",
        "skew-symmetric": "a mass or stiffness matrix is symmetric, not skew-symmetric",
    }
    if field in why or sym in why:
        raise InputError(param, str(path), _MM_ALLOWED, why.get(field) or why[sym])
    if (
        fmt not in ("coordinate", "array")
        or field not in ("real", "double", "integer", "complex")
        or sym not in ("general", "symmetric", "hermitian")
    ):
        raise InputError(param, str(path), _MM_ALLOWED, f"unknown header {' '.join(head)!r}")
    try:
        m = scipy.io.mmread(str(path))
    except (ValueError, OSError, IndexError, TypeError) as e:
        raise InputError(param, str(path), _MM_ALLOWED, str(e)[:160]) from None
    if sp.issparse(m):
        coo = m.tocoo()
        keys = coo.row.astype(np.int64) * max(coo.shape[1], 1) + coo.col
        if np.unique(keys).size != keys.size:
            raise InputError(
                param,
                str(path),
                "each entry once",
                "an entry is given twice, or a symmetric file gives both triangles",
            )
    return _as_matrix(m, param)


def read_harwell_boeing(path: str | Path, param: str = "model.matrices") -> sp.csr_matrix:
    """A real assembled Harwell-Boeing file (``scipy.io.hb_read``).

    scipy reads only unsymmetric (``RUA``) files; a symmetric ``RSA`` file
    (as ANSYS ``HBMAT`` writes) stores one triangle with the same layout, so
    it is read as ``RUA`` and mirrored.
    """
    import scipy.io

    text = _text(Path(path), param, "a Harwell-Boeing text file")
    lines = text.splitlines(keepends=True)
    symmetric = len(lines) > 2 and lines[2][:3].upper() == "RSA"
    if symmetric:
        lines[2] = "RUA" + lines[2][3:]
    try:
        m = scipy.io.hb_read(io.StringIO("".join(lines))).tocsr()
    except (ValueError, IndexError, TypeError) as e:
        raise InputError(
            param, str(path), "a real assembled Harwell-Boeing file (RUA or RSA)", str(e)[:160]
        ) from None
    if symmetric:
        m = (m + m.T - sp.diags(m.diagonal())).tocsr()
    return m


# -- dispatch -----------------------------------------------------------------------------


def file_kind(path: Path, param: str = "model.matrices") -> str:
    """``op4``, ``dmig``, ``abaqus``, ``mm``, ``hb`` or ``numpy`` from suffix (and content)."""
    s = path.suffix.lower()
    if s in OP4_SUFFIXES:
        return "op4"
    if s in DMIG_SUFFIXES:
        return "dmig"
    if s in HB_SUFFIXES:
        return "hb"
    if s in MM_SUFFIXES:
        return "mm"
    if s in NUMPY_SUFFIXES:
        return "numpy"
    if s in MTX_SUFFIXES:
        with path.open("rb") as fh:
            head = fh.read(64)
        return "mm" if head.lstrip().lower().startswith(b"%%matrixmarket") else "abaqus"
    raise InputError(param, str(path), "a file ending in " + " ".join(SUFFIXES))


_KIND_NAMES = {
    "op4": "Nastran OP4",
    "dmig": "Nastran DMIG punch",
    "abaqus": "Abaqus .mtx",
    "mm": "Matrix Market",
    "hb": "Harwell-Boeing",
    "numpy": ".npz or HDF5",
}


def read_file(
    path: str | Path, param: str = "model.matrices"
) -> tuple[dict[str, Any], tuple[Label, ...] | None]:
    """All matrices of one file by name, and its row labels if it has them.

    A file holding a single matrix (Abaqus, Matrix Market, Harwell-Boeing)
    gives it under the file's stem. ``param`` is the input that named the
    file: every failure to read it is an InputError naming ``param`` and the
    file, whatever the format's reader raised.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(param, str(path), "an existing file")
    kind = file_kind(path, param)
    try:
        if kind == "op4":
            return read_op4(path, param=param), None
        if kind == "dmig":
            return read_dmig(path, param)
        if kind == "abaqus":
            m, labels = read_abaqus_mtx(path, param)
            return {path.stem: m}, labels
        if kind == "mm":
            return {path.stem: read_matrix_market(path, param)}, None
        if kind == "hb":
            return {path.stem: read_harwell_boeing(path, param)}, None
        return _read_numpy(path), None
    except (WorkbenchError, MemoryError):
        raise
    except Exception as e:  # noqa: BLE001 - any reader failure is a bad file, named here
        raise InputError(
            param,
            str(path),
            f"a readable {_KIND_NAMES[kind]} file",
            f"{type(e).__name__}: {str(e)[:160]}",
        ) from None


def _text(path: Path, param: str, what: str) -> str:
    """The text of ``path``; a binary or unreadable file is an InputError naming ``param``."""
    try:
        return path.read_text(encoding="utf-8")
    except UnicodeDecodeError as e:
        raise InputError(
            param,
            str(path),
            what,
            f"byte 0x{e.object[e.start]:02x} at offset {e.start} is not text",
        ) from None
    except OSError as e:
        raise InputError(param, str(path), f"a readable file ({what})", e.strerror or "") from None


def read_matrices(
    files: dict[str, str | Path],
    dof_map: str | Path | None = None,
    file_param: str | None = None,
) -> MatrixSet:
    """Read named matrices, each ``"file"`` or ``"file#NAME"``, onto one row numbering.

    ``files`` maps the role (``"mass"``, ``"stiffness"``, ...) to where the
    matrix is. Labelled matrices (DMIG, Abaqus) are placed on the sorted
    union of their labels, so a mass matrix that omits massless DOFs still
    lines up with the stiffness. Unlabelled ones must all have the same size;
    ``dof_map`` then gives their labels. ``file_param``: the input that
    named the files (default ``model.<role>`` of each), named by the errors.
    """
    cache: dict[Path, tuple[dict[str, Any], tuple[Label, ...] | None]] = {}
    got: dict[str, tuple[Any, tuple[Label, ...] | None]] = {}
    for role, spec in files.items():
        fname, _, name = str(spec).partition("#")
        path = Path(fname)
        if path not in cache:
            cache[path] = read_file(path, file_param or f"model.{role}")
        arrays, labels = cache[path]
        if not name:
            if len(arrays) != 1:
                raise InputError(
                    f"model.{role}",
                    str(spec),
                    f"'{path.name}#NAME' with NAME one of " + ", ".join(arrays),
                )
            name = next(iter(arrays))
        if name not in arrays:
            raise InputError(
                f"model.{role}",
                str(spec),
                f"a matrix of {path.name}: " + ", ".join(sorted(arrays)),
                did_you_mean(name, arrays),
            )
        got[role] = (arrays[name], labels)
    labelled = [lab for _, lab in got.values() if lab is not None]
    source = ", ".join(sorted({p.name for p in cache}))
    if labelled:
        if dof_map:
            raise InputError(
                "model.dof_map", str(dof_map), "empty", f"{source} carries its own node labels"
            )
        _check_shared_nodes(got, files)
        union = tuple(sorted({lab for labs in labelled for lab in labs}))
        index = {lab: i for i, lab in enumerate(union)}
        out = {}
        for role, (m, labs) in got.items():
            if labs is None:
                raise InputError(
                    f"model.{role}",
                    str(files[role]),
                    "a file with node labels like the others (DMIG or Abaqus)",
                )
            out[role] = _relabel(m, labs, index, len(union))
        return MatrixSet(out, union, source)
    sizes = {role: m.shape for role, (m, _) in got.items()}
    n = next(iter(sizes.values()))[0]
    for role, shape in sizes.items():
        if shape[0] != n or (len(shape) == 2 and shape[1] not in (n, 1)):
            raise InputError(
                f"model.{role}", str(files[role]), f"a {n} x {n} matrix", f"it is {shape}"
            )
    labels = None
    if dof_map:
        labels = read_dof_map(dof_map)
        if len(labels) != n:
            raise InputError(
                "model.dof_map", str(dof_map), f"{n} rows (one per DOF)", f"it has {len(labels)}"
            )
    return MatrixSet({role: m for role, (m, _) in got.items()}, labels, source)


def _check_shared_nodes(got: dict[str, tuple[Any, Any]], files: dict[str, Any]) -> None:
    """Labelled matrices of one model share nodes: disjoint node ids are two models."""
    nodes = {role: {n for n, _ in labs} for role, (_, labs) in got.items() if labs}
    if "stiffness" not in nodes:
        return
    ref = nodes["stiffness"]
    for role, ids in nodes.items():
        if role != "stiffness" and ids and not ids & ref:
            raise InputError(
                f"model.{role}",
                str(files[role]),
                "a matrix on the nodes of model.stiffness",
                f"its node ids {min(ids)}..{max(ids)} share none with the stiffness's "
                f"{min(ref)}..{max(ref)}",
            )


def _relabel(m, labs, index, n):
    perm = np.array([index[lab] for lab in labs])
    coo = sp.coo_matrix(m)
    return sp.csr_matrix((coo.data, (perm[coo.row], perm[coo.col])), shape=(n, n))


def _as_matrix(a: Any, param: str = "model.matrices") -> Any:
    """A matrix read by a format's reader, checked (real, finite, a valid structure)."""
    return check_matrix(a, param, square=False)


def _read_numpy(path: Path) -> dict[str, Any]:
    if path.suffix == ".npz":
        with np.load(path, allow_pickle=False) as z:
            return {k: z[k] for k in z.files}
    import h5py

    out: dict[str, Any] = {}
    with h5py.File(path, "r") as h:

        def visit(name, obj):
            if isinstance(obj, h5py.Dataset):
                out[name] = obj[()]

        h.visititems(visit)
    return out


def _quiet_log():
    from cpylog import SimpleLogger

    return SimpleLogger(level="error")

"""Reduced matrices from FE codes: each format written here, read back, and used by node id.

The model: two nodes with three translations each, node 11 on the damper
and node 21 on the platform, a symmetric positive definite K (N/m) and a
lumped M (kg). Every format is written by its own library where one exists
(pyNastran for OP4 and DMIG, scipy.io for Matrix Market and Harwell-Boeing)
and by hand for Abaqus (plain text), then read through the model TOML with
the contact pair named by node id; the system must equal the one built from
a ``.npz`` with DOF indices, to the digits each text format keeps (rtol
1e-12 where the writer prints 15 or more significant digits, 1e-9 for the
DMIG large field, 1e-7 for scipy's Harwell-Boeing writer).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.io
import scipy.sparse as sp

from workbench import readers
from workbench.errors import InputError
from workbench.hbm import load_frf_model

LABELS = [(11, 1), (11, 2), (11, 3), (21, 1), (21, 2), (21, 3)]
RTOL = 1e-12


def _model():
    rng = np.random.default_rng(3)
    a = rng.normal(size=(6, 6))
    K = (a @ a.T + 6 * np.eye(6)) * 1e4
    K[0, 5] = K[5, 0] = 0.0  # a structural zero, as in real exports
    M = np.diag([0.1, 0.1, 0.1, 0.3, 0.3, 0.3])
    return M, K


TAIL = """
damping_ratio = 0.01
[excitation]
dofs = {exc}
amplitudes_n = [1.0]
levels = [1.0]
[band]
start_hz = 10.0
end_hz = 20.0
[output]
dofs = {out}
[[contact]]
{contact}
mu = 0.3
kt_n_per_m = 1e4
kn_n_per_m = 1e4
n0_n = 1.0
"""
BY_NODE = dict(
    exc="[[11, 1]]",
    out='[[11, 1], [11, "UZ"]]',
    contact="nodes = [11]\nother_nodes = [21]\ncomponents = [1, 2, 3]",
)
BY_INDEX = dict(exc="[0]", out="[0, 2]", contact="dofs = [[0, 1, 2]]\nother = [[3, 4, 5]]")


def _toml(tmp_path: Path, model: str, **kw) -> Path:
    p = tmp_path / "m.toml"
    p.write_text("[model]\n" + model + TAIL.format(**{**BY_NODE, **kw}))
    return p


def _reference(tmp_path: Path):
    M, K = _model()
    ref = tmp_path / "ref"
    ref.mkdir()
    np.savez(ref / "m.npz", M=M, K=K)
    return load_frf_model(_toml(ref, 'matrices = "m.npz"', **BY_INDEX))


def _same_system(m, ref, rtol=RTOL):
    for name in ("M", "K"):
        a, b = getattr(m.system, name), getattr(ref.system, name)
        a = a.toarray() if sp.issparse(a) else a
        b = b.toarray() if sp.issparse(b) else b
        np.testing.assert_allclose(a, b, rtol=rtol, atol=rtol * np.abs(b).max())
    np.testing.assert_array_equal(m.system.contacts.W.toarray(), ref.system.contacts.W.toarray())
    np.testing.assert_array_equal(m.outputs, ref.outputs)
    np.testing.assert_array_equal(m.f1, ref.f1)


def _write_dof_map(path: Path, ansys: bool = False) -> None:
    names = {1: "UX", 2: "UY", 3: "UZ"}
    if ansys:  # the .mapping file of ANSYS HBMAT
        rows = ["Matrix Eqn   Node   DOF"]
        rows += [f"{i + 1:10d} {n:6d} {names[c]:>5s}" for i, (n, c) in enumerate(LABELS)]
    else:
        rows = ["# node component"] + [f"{n} {c}" for n, c in LABELS]
    path.write_text("\n".join(rows) + "\n")


def test_op4_with_dof_map(tmp_path):
    from pyNastran.op2.result_objects.matrix import Matrix
    from pyNastran.op4.op4 import write_op4

    M, K = _model()
    write_op4(
        tmp_path / "m.op4",
        {"MAAX": Matrix("MAAX", 6, data=M), "KAAX": Matrix("KAAX", 6, data=sp.coo_matrix(K))},
        is_binary=False,
        precision="double",
    )
    mats = readers.read_op4(tmp_path / "m.op4")
    np.testing.assert_allclose(mats["KAAX"].toarray(), K, rtol=RTOL)
    _write_dof_map(tmp_path / "dofs.txt")
    p = _toml(
        tmp_path, 'matrices = "m.op4"\nmass = "MAAX"\nstiffness = "KAAX"\ndof_map = "dofs.txt"'
    )
    _same_system(load_frf_model(p), _reference(tmp_path))


def test_dmig_punch(tmp_path):
    from pyNastran.bdf.bdf import BDF

    M, K = _model()
    bdf = BDF(debug=None)
    order = [3, 4, 5, 0, 1, 2]  # platform node first: the reader sorts by (node, component)
    for name, A in (("MAAX", M), ("KAAX", K)):
        gcj, gci, vals = [], [], []
        for jj, j in enumerate(order):
            for i in order[jj:]:
                if A[i, j] != 0.0:
                    gcj.append(LABELS[j]), gci.append(LABELS[i]), vals.append(A[i, j])
        bdf.add_dmig(name, 6, 2, 0, 0, None, gcj, gci, vals)
    bdf.write_bdf(tmp_path / "m.pch", enddata=False, size=16, is_double=True)
    mats, labels = readers.read_dmig(tmp_path / "m.pch")
    assert list(labels) == LABELS
    # a 16-character large field holds 10 significant digits (D+04 takes the rest)
    np.testing.assert_allclose(mats["KAAX"].toarray(), K, rtol=1e-9)
    p = _toml(tmp_path, 'matrices = "m.pch"\nmass = "MAAX"\nstiffness = "KAAX"')
    _same_system(load_frf_model(p), _reference(tmp_path), rtol=1e-9)


def _write_abaqus(path: Path, A: np.ndarray, rows: list[int]) -> None:
    lines = ["** written by test_readers: lower triangle, MATRIX INPUT format"]
    for i in rows:
        for j in rows:
            if j <= i and A[i, j] != 0.0:
                (ni, ci), (nj, cj) = LABELS[i], LABELS[j]
                lines.append(f"{ni},{ci}, {nj},{cj}, {A[i, j]:.17e}")
    path.write_text("\n".join(lines) + "\n")


def test_abaqus_mtx(tmp_path):
    M, K = _model()
    _write_abaqus(tmp_path / "job_MASS2.mtx", M, list(range(6)))
    _write_abaqus(tmp_path / "job_STIF2.mtx", K, list(range(6)))
    m, labels = readers.read_abaqus_mtx(tmp_path / "job_STIF2.mtx")
    assert list(labels) == LABELS
    np.testing.assert_allclose(m.toarray(), K, rtol=RTOL)
    p = _toml(tmp_path, 'matrices = ""\nmass = "job_MASS2.mtx"\nstiffness = "job_STIF2.mtx"')
    _same_system(load_frf_model(p), _reference(tmp_path))
    # a mass matrix without its massless DOFs (Abaqus writes no line for them)
    # lines up with the stiffness on the union of the labels
    M0 = M.copy()
    M0[3:, 3:] = 0.0
    _write_abaqus(tmp_path / "rigid_MASS2.mtx", M0, [0, 1, 2])
    ms = readers.read_matrices(
        {"mass": tmp_path / "rigid_MASS2.mtx", "stiffness": tmp_path / "job_STIF2.mtx"}
    )
    assert ms.labels == tuple(LABELS) and ms.index(21, 3) == 5
    np.testing.assert_allclose(ms.matrices["mass"].toarray(), M0, rtol=RTOL)


def test_matrix_market_and_harwell_boeing_with_ansys_mapping(tmp_path):
    M, K = _model()
    _mmwrite(tmp_path / "K.mtx", K, symmetry="symmetric")
    _mmwrite(tmp_path / "M.mm", M)
    scipy.io.hb_write(str(tmp_path / "M.rua"), sp.csc_matrix(M))
    # a symmetric RSA file holds the lower triangle (what ANSYS HBMAT writes)
    scipy.io.hb_write(str(tmp_path / "K.rsa"), sp.csc_matrix(np.tril(K)))
    text = (tmp_path / "K.rsa").read_text().splitlines(keepends=True)
    text[2] = "RSA" + text[2][3:]
    (tmp_path / "K.rsa").write_text("".join(text))
    assert readers.file_kind(tmp_path / "K.mtx") == "mm"
    np.testing.assert_allclose(
        readers.read_harwell_boeing(tmp_path / "K.rsa").toarray(), K, rtol=1e-7
    )  # scipy's hb_write prints 8 significant digits
    _write_dof_map(tmp_path / "full.mapping", ansys=True)
    ref = _reference(tmp_path)
    for mass, stiff, rtol in (("M.mm", "K.mtx", RTOL), ("M.rua", "K.rsa", 1e-7)):
        p = _toml(
            tmp_path,
            f'matrices = ""\nmass = "{mass}"\nstiffness = "{stiff}"\ndof_map = "full.mapping"',
        )
        got = load_frf_model(p)
        np.testing.assert_allclose(
            _dense(got.system.K), ref.system.K, rtol=rtol, atol=rtol * np.abs(ref.system.K).max()
        )
        np.testing.assert_allclose(_dense(got.system.M), ref.system.M, rtol=rtol)
        np.testing.assert_array_equal(
            got.system.contacts.W.toarray(), ref.system.contacts.W.toarray()
        )


def _mmwrite(path: Path, A, **kw) -> None:
    with open(path, "wb") as fh:  # a file name without .mtx would get one appended
        scipy.io.mmwrite(fh, sp.coo_matrix(A), precision=17, **kw)


def _dense(a):
    return a.toarray() if sp.issparse(a) else np.asarray(a)


@pytest.mark.parametrize(
    "model, edit, param",
    [
        ('matrices = "m.npz"', ("nodes = [11]", "nodes = [12]"), "contact[0].nodes"),
        (
            'matrices = "m.npz"',
            ("components = [1, 2, 3]", "components = [1, 2, 7]"),
            "contact[0].components",
        ),
        ('matrices = "m.npz"', ('dof_map = "dofs.txt"', ""), "contact[0].nodes"),
        ('matrices = "m.npz"', ('"UZ"', '"UW"'), "output.dofs[1]"),
        ('matrices = ""\nmass = "M.mm"\nstiffness = "nope.mm"', None, "model.stiffness"),
        ('matrices = "m.op4"\nmass = "MAAX"\nstiffness = "KAX"', None, "model.stiffness"),
    ],
)
def test_reader_errors_name_the_key(tmp_path, model, edit, param):
    from pyNastran.op2.result_objects.matrix import Matrix
    from pyNastran.op4.op4 import write_op4

    M, K = _model()
    np.savez(tmp_path / "m.npz", M=M, K=K)
    _mmwrite(tmp_path / "M.mm", M)
    write_op4(
        tmp_path / "m.op4",
        {"MAAX": Matrix("MAAX", 2, data=M), "KAAX": Matrix("KAAX", 2, data=K)},
        is_binary=False,
    )
    _write_dof_map(tmp_path / "dofs.txt")
    text = "[model]\n" + model + '\ndof_map = "dofs.txt"' + TAIL.format(**BY_NODE)
    if edit:
        text = text.replace(*edit)
    (tmp_path / "m.toml").write_text(text)
    with pytest.raises(InputError) as e:
        load_frf_model(tmp_path / "m.toml")
    assert e.value.param == param
    assert "\n" not in str(e.value)


def test_abaqus_mixed_triangles_refused(tmp_path):
    (tmp_path / "k.mtx").write_text(
        "1,1, 1,1, 2.0\n2,1, 1,1, -1.0\n1,1, 2,1, -1.0\n"
        "2,1, 3,1, -1.0\n3,1, 3,1, 2.0\n2,1, 2,1, 2.0\n"
    )
    with pytest.raises(InputError, match="mirror"):
        readers.read_abaqus_mtx(tmp_path / "k.mtx")

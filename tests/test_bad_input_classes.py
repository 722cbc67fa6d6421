"""Issue 34: each class of bad input is refused at its root, for every option of the class.

The table of tests/data/bad_inputs.toml holds examples of each class; the
tests here go over the whole class: every matrix defect in every role,
every whole-number option of every command, every command's output folder,
every physical option's range, every path argument's encoding. Each run is
in-process with meshing and the harmonic balance booby-trapped
(``_no_work``), so a refusal that came only after work started fails.
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from tests.conftest import ROOT, run_upd
from tests.test_cli_bad_inputs import ERROR_LINE, _no_work, run_inprocess
from workbench import readers
from workbench.errors import InputError
from workbench.hbm import load_frf_model

EX = ROOT / "studies" / "examples" / "sdof_jenkins.toml"
TINY = ROOT / "tests" / "studies" / "tiny.toml"
# the least each command needs besides the option under test
BASE = {
    "frf": ["frf", str(EX)],
    "nlmodes": ["nlmodes", str(EX)],
    "study": ["study"],
    "screen": ["screen"],
    "mesh": ["mesh", "--damper", "cone"],
    "modes": ["modes", "--damper", "cone"],
    "reduce": ["reduce", "--damper", "cone"],
    "analytic": ["analytic"],
    "disk": ["disk", "--damper", "cone"],
}


def refused(argv: list[str], cwd: Path, monkeypatch) -> str:
    """Run ``upd argv``; assert exit 2 with one error line and no work; return the line."""
    _no_work(monkeypatch)
    code, _, err = run_inprocess([str(a) for a in argv], cwd)
    lines = [ln for ln in err.splitlines() if ERROR_LINE.match(ln)]
    assert "Traceback" not in err and "internal error" not in err, err[-1500:]
    assert code == 2 and len(lines) == 1, err[-1500:]
    return lines[0]


def test_the_no_work_trap_springs(tmp_path, monkeypatch):
    """A check of the check: a good input does reach the trapped meshing and solving."""
    _no_work(monkeypatch)
    for argv in (["mesh", "--damper", "cone"], ["frf", str(EX), "--levels", "1"]):
        code, _, err = run_inprocess([*argv, "--out", str(tmp_path / argv[0])], tmp_path)
        assert code in (1, 3) and "work started" in err, err[-800:]


# -- class 1: matrices read from files ----------------------------------------------------

M1, K1 = np.eye(1) * 0.1, np.eye(1) * 39478.4


def _csr(indices, indptr=(0, 1), shape=(1, 1), data=(39478.4,)):
    return {"data": np.array(data), "indices": np.array(indices), "indptr": np.array(indptr),
            "shape": np.array(shape)}  # fmt: skip


MATRIX_DEFECTS = {  # name -> (the matrix as stored, a needle of the refusal)
    "csr index beyond": (_csr([7]), "column index 7"),
    "csr index negative": (_csr([-3]), "column index -3"),
    "csr indptr falling": (_csr([0, 0], (0, 2, 1), data=(1.0, 1.0)), "indptr"),
    "csr indptr length": (_csr([0], (0, 1, 1)), "row offsets"),
    "csr parts differ": (_csr([0, 0]), "column indices"),
    "csr shape three": (_csr([0], shape=(1, 1, 1)), "shape"),
    "csr float indices": (_csr([0.5]), "whole numbers in indices"),
    "complex": (K1 * (1 + 1j), "complex values"),
    "nan": (K1 * np.nan, "NaN or infinite"),
    "inf": (K1 * np.inf, "NaN or infinite"),
    "huge": (K1 * 1e300, "largest entry"),
    "tiny": (K1 * 1e-300, "largest entry"),
    "text": (np.array([["a"]]), "values of type"),
    "not square": (np.ones((1, 2)), "shape (1, 2)"),
    "vector": (np.ones(1), "shape (1,)"),
    "wrong size": (np.eye(2), "(1, 1), the size of the mass matrix"),
}


def _model_file(d: Path, arrays: dict, extra: str = "") -> Path:
    with (d / "x.npz").open("wb") as fh:
        np.savez(fh, **arrays)
    f = d / "m.toml"
    f.write_text(
        f'[model]\nmatrices = "x.npz"\n{extra}\n[excitation]\ndofs = [0]\namplitudes_n = [1.0]\n'
        "[band]\nstart_hz = 80.0\nend_hz = 170.0\n[output]\ndofs = [0]\n[[contact]]\n"
        "dofs = [0]\nkt_n_per_m = 39478.0\nn0_n = 2.0\n"
    )
    return f


ROLE_DEFECTS = [
    (role, defect)
    for role in ("mass", "stiffness", "damping")
    for defect in MATRIX_DEFECTS
    if not (role == "mass" and defect == "wrong size")  # the mass matrix sets the size
]


@pytest.mark.parametrize("role, defect", ROLE_DEFECTS)
def test_every_matrix_defect_in_every_role_is_refused_naming_the_role(tmp_path, role, defect):
    bad, needle = MATRIX_DEFECTS[defect]
    arrays = {"M": M1, "K": K1, "C": M1 * 0.0}
    key = {"mass": "M", "stiffness": "K", "damping": "C"}[role]
    if isinstance(bad, dict):
        del arrays[key]
        arrays.update({f"{key}_{k}": v for k, v in bad.items()})
    else:
        arrays[key] = bad
    f = _model_file(tmp_path, arrays, 'damping = "C"')
    with pytest.raises(InputError) as e:
        load_frf_model(f)
    assert e.value.param == f"model.{role}" and needle in str(e.value), str(e.value)


@pytest.mark.parametrize("role", ["mass", "stiffness"])
def test_mass_and_stiffness_must_be_symmetric(tmp_path, role):
    M, K = np.eye(2) * 0.1, np.array([[4e4, 2e4], [2e4, 8e4]])
    A = M if role == "mass" else K
    A[0, 1] += 0.1 * A.max()
    f = _model_file(tmp_path, {"M": M, "K": K})
    with pytest.raises(InputError, match=f"model.{role} = 'asymmetry"):
        load_frf_model(f)


# the CSR defects a scipy.sparse matrix itself can hold (its shape and index type are its own)
SCIPY_CSR = ["csr index beyond", "csr index negative", "csr indptr falling", "csr indptr length",
             "csr parts differ"]  # fmt: skip


@pytest.mark.parametrize("defect", SCIPY_CSR)
def test_a_bad_sparse_matrix_never_reaches_scipy_through_the_api(defect):
    """System (the API's entry) checks a scipy CSR's parts too: a bad one never crashes."""
    from workbench.hbm.core.system import System

    parts = MATRIX_DEFECTS[defect][0]
    K = sp.csr_matrix(K1)
    K.data, K.indices, K.indptr = (np.asarray(parts[k]) for k in ("data", "indices", "indptr"))
    with pytest.raises(InputError):
        System(M=M1, K=K)


@pytest.mark.parametrize("defect", ["csr index beyond", "csr index negative"])
def test_a_bad_sparse_index_is_exit_2_never_a_crash(tmp_path, defect):
    """The segmentation fault of the issue (2 runs in 4): three runs, each a clean exit 2."""
    arrays = {"M": M1, **{f"K_{k}": v for k, v in MATRIX_DEFECTS[defect][0].items()}}
    f = _model_file(tmp_path, arrays)
    for _ in range(3):
        r = run_upd("frf", f, "--out", tmp_path / "o", timeout=120)
        assert r.code == 2 and "model.stiffness" in r.err, r


# -- class 5: a file that cannot be read is named by its own key -----------------------------


@pytest.mark.parametrize("suffix", readers.SUFFIXES)
@pytest.mark.parametrize("role", ["mass", "stiffness"])
def test_an_unreadable_matrix_file_is_blamed_on_its_own_key(tmp_path, suffix, role):
    good = "%%MatrixMarket matrix coordinate real symmetric\n1 1 1\n1 1 0.1\n"
    (tmp_path / "good.mm").write_text(good)
    (tmp_path / f"bad{suffix}").write_bytes(bytes.fromhex("e7f40a9cff00fe88117f"))
    files = {"mass": "good.mm", "stiffness": "good.mm", role: f"bad{suffix}"}
    f = tmp_path / "m.toml"
    f.write_text(
        f'[model]\nmatrices = ""\nmass = "{files["mass"]}"\nstiffness = "{files["stiffness"]}"\n'
        "[excitation]\ndofs = [0]\namplitudes_n = [1.0]\n[band]\nstart_hz = 80.0\n"
        "end_hz = 170.0\n[output]\ndofs = [0]\n[[contact]]\ndofs = [0]\nkt_n_per_m = 1.0\n"
    )
    with pytest.raises(InputError) as e:
        load_frf_model(f)
    assert e.value.param == f"model.{role}" and f"bad{suffix}" in str(e.value.value), e.value


@pytest.mark.parametrize(
    "header, needle",
    [
        ("%%MatrixMarket matrix coordinate pattern symmetric", "no values"),
        ("%%MatrixMarket matrix coordinate real skew-symmetric", "skew-symmetric"),
        ("%%MatrixMarket vector coordinate real general", "its first line"),
        ("%%MatrixMarket matrix coordinate real", "its first line"),
        ("%%MatrixMarket matrix coordinate reel general", "unknown header"),
        ("%%MatrixMarket matrix kordinate real general", "unknown header"),
        ("%%MatrixMarket matrix coordinate real symetric", "unknown header"),
        ("% a comment first", "its first line"),
    ],
)
def test_a_matrix_market_header_is_read_strictly(tmp_path, header, needle):
    p = tmp_path / "K.mm"
    p.write_text(f"{header}\n1 1 1\n1 1 39478.4\n")
    with pytest.raises(InputError, match=needle) as e:
        readers.read_matrix_market(p, "model.stiffness")
    assert e.value.param == "model.stiffness"


def test_mass_and_stiffness_on_disjoint_nodes_are_two_models(tmp_path):
    (tmp_path / "M.mtx").write_text("1, 1, 1, 1, 0.1\n2, 1, 2, 1, 0.1\n")
    (tmp_path / "K.mtx").write_text("5, 1, 5, 1, 4e4\n6, 1, 6, 1, 8e4\n")
    with pytest.raises(InputError, match="share none with the stiffness's 5..6") as e:
        readers.read_matrices({"mass": tmp_path / "M.mtx", "stiffness": tmp_path / "K.mtx"})
    assert e.value.param == "model.mass"


# -- class 2: the output folder --------------------------------------------------------------

COMMANDS = [*BASE, "report"]


def _argv(command: str, d: Path) -> list[str]:
    if command == "report":
        (d / "r").mkdir(exist_ok=True)
        (d / "r" / "manifest.json").write_text('{"title": "t", "sections": []}')
        return ["report", str(d / "r")]
    return list(BASE[command])


@pytest.mark.parametrize("kind", ["read-only", "a file", "empty", "cannot be created"])
@pytest.mark.parametrize("command", COMMANDS)
def test_every_command_refuses_an_unusable_output_folder_before_any_work(
    tmp_path, monkeypatch, command, kind
):
    target = {
        "read-only": tmp_path / "ro",
        "a file": tmp_path / "afile",
        "empty": "",
        "cannot be created": "/proc/x",
    }[kind]
    (tmp_path / "afile").write_text("x")
    (tmp_path / "ro").mkdir()
    import workbench.cli.main as cli

    real = cli.unwritable
    monkeypatch.setattr(
        cli,
        "unwritable",
        lambda p: "Read-only file system" if Path(p) == tmp_path / "ro" else real(p),
    )
    line = refused([*_argv(command, tmp_path), "--out", str(target)], tmp_path, monkeypatch)
    assert f"--out = '{target}'" in line, line


def test_the_write_probe_writes(tmp_path):
    """unwritable() creates and removes a real file: /proc takes none even for root."""
    from workbench.io import unwritable

    assert unwritable("/proc") is not None
    assert unwritable(tmp_path) is None and not list(tmp_path.iterdir())


def test_report_into_a_study_folder_it_cannot_write_is_refused(tmp_path, monkeypatch):
    import workbench.io

    monkeypatch.setattr(workbench.io, "unwritable", lambda p: "Read-only file system")
    line = refused(_argv("report", tmp_path), tmp_path, monkeypatch)
    assert "DIR" in line and "Read-only file system" in line and "--out" in line


@pytest.mark.parametrize("command", ["frf", "nlmodes"])
def test_a_write_that_fails_after_the_solve_loses_nothing(tmp_path, monkeypatch, command):
    """The disk fills after the check: the results go to a rescue folder, named."""
    from workbench.hbm.forced.branch import Branch
    from workbench.hbm.nlmodes.record import NlModeBranch

    want = tmp_path / "o"
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "tmp"))
    (tmp_path / "tmp").mkdir()
    for cls in (Branch, NlModeBranch):
        real = cls.save

        def save(self, path, real=real):
            if Path(path).parent == want:
                raise OSError(28, "No space left on device")
            return real(self, path)

        monkeypatch.setattr(cls, "save", save)
    argv = [command, str(EX), "--levels", "1", "--out", str(want), "--json"]
    code, out, err = run_inprocess(argv, tmp_path)
    assert code == 0, err[-1500:]
    s = json.loads(out)
    rescue = Path(s["out"])
    assert rescue.parent == tmp_path / "tmp" and "No space left on device" in s["out_note"]
    assert (rescue / "summary.json").is_file() and any(rescue.glob("*.h5"))
    assert "written to" in err and str(rescue) in err


# -- class 3: one rule for every whole number ------------------------------------------------


def _int_options() -> list[tuple[str, str, list[str]]]:
    """(command, flag, base argv) of every whole-number option of every command."""
    from workbench.cli.main import build_parser
    from workbench.cli.values import value_actions
    from workbench.studies.engine.spec import OPTIONS

    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    out = []
    for command, p in sub.choices.items():
        base = BASE.get(command)
        if base is None:
            continue
        for a in value_actions(p):
            if a.value.kind in ("int", "ints"):
                out.append((command, a.option_strings[-1], base))
        if command in ("study", "screen", "nlmodes"):
            for o in OPTIONS:
                if o.kind in ("int", "ints"):
                    b = base if command != "nlmodes" else ["nlmodes", str(TINY)]
                    out.append((command, f"--{o.name}", b))
    return out


INT_OPTIONS = _int_options()


def test_the_whole_number_options_are_all_found():
    flags = {(c, f) for c, f, _ in INT_OPTIONS}
    assert len(INT_OPTIONS) >= 40
    for c, f in (
        ("frf", "--nt"),
        ("modes", "--n"),
        ("reduce", "--modes"),
        ("study", "--uq-seed"),
        ("nlmodes", "--steps"),
        ("analytic", "--points"),
        ("screen", "--max-points"),
    ):
        assert (c, f) in flags, (c, f)


@pytest.mark.parametrize("value", ["nan", "inf", "-inf", "1.5", "abc", "1e400"])
@pytest.mark.parametrize(
    "command, flag, base", INT_OPTIONS, ids=[f"{c} {f}" for c, f, _ in INT_OPTIONS]
)
def test_every_whole_number_option_refuses_what_is_not_one(
    tmp_path, monkeypatch, command, flag, base, value
):
    line = refused([*base, flag, value, "--out", str(tmp_path / "o")], tmp_path, monkeypatch)
    assert flag.lstrip("-") in line and "a whole number" in line, line


# -- class 4: physical ranges, memory, conditioning ------------------------------------------


def _soft_options():
    from workbench.studies.engine.spec import OPTIONS

    return [o for o in OPTIONS if o.soft_lo is not None or o.soft_hi is not None]


SOFT_BOUNDS = [
    (o, side)
    for o in _soft_options()
    for side, bound in (("above", o.soft_hi), ("below", o.soft_lo))
    if bound is not None
]


@pytest.mark.parametrize("o, side", SOFT_BOUNDS, ids=[f"{o.name} {s}" for o, s in SOFT_BOUNDS])
def test_a_physical_range_says_why_and_yields_to_allow_extreme(o, side):
    from workbench.studies.engine.spec import resolve

    bound = o.soft_hi if side == "above" else o.soft_lo
    v = bound * (1e3 if side == "above" else 1e-3)
    value = [v, v * 1.01] if o.name.startswith("band") else ([v] if o.kind == "floats" else v)
    with pytest.raises(InputError) as e:
        resolve({o.name: value})
    assert o.why in str(e.value) and "allow-extreme" in str(e.value)
    assert resolve({o.name: value, "allow-extreme": True}).allow_extreme


def test_the_physical_options_are_all_bounded():
    names = {o.name for o in _soft_options()}
    assert {"forces", "cf", "kt-line", "kn-line", "kt-face", "kn-face"} <= names
    assert {"band-in-phase", "band-out-of-phase", "uq-threshold"} <= names


def test_a_band_wider_than_a_decade_is_refused_unless_extreme():
    from workbench.studies.engine.spec import resolve

    with pytest.raises(InputError, match="hi <= 10 x lo"):
        resolve({"band-out-of-phase": [100.0, 2000.0]})
    assert resolve({"band-out-of-phase": [100.0, 2000.0], "allow-extreme": True})


@pytest.mark.parametrize(
    "old, new, param",
    [
        ("nt = 128", "nt = 1000000000", "hbm.nt"),
        ("nt = 128", "nt = 8", "hbm.nt"),
        ("harmonics = [0, 1, 2, 3, 4, 5, 6, 7]", "harmonics = [0, 1, 300]", "hbm.harmonics[2]"),
        ("mu = 0.5", "mu = 30.0", "contact[0].mu"),
        ("kt_n_per_m = 39478.4176", "kt_n_per_m = 1.0e20", "contact[0].kt_n_per_m"),
        ("n0_n = 2.0", "n0_n = 1.0e300", "contact[0].n0_n"),
        ("levels = [0.2, 0.5, 1.0, 2.0]", "levels = [1.0e30]", "excitation.levels[0]"),
        ("amplitudes_n = [1.0]", "amplitudes_n = [1.0e300]", "excitation.amplitudes_n[0]"),
        ("start_hz = 80.0", "start_hz = 1.0e-9", "band"),
        ("[band]", "[solver]\nmax_points = 1000000000\n[band]", "solver.max_points"),
        ("[band]", "[solver]\nn_fine = 1000000000\n[band]", "solver.n_fine"),
        ("[band]", "[solver]\nrefresh_ksp_its = 1000000000\n[band]", "solver.refresh_ksp_its"),
        ("[band]", "[solver]\nsingle_above = 1000000000000\n[band]", "solver.single_above"),
    ],
)
def test_a_model_file_value_beyond_its_range_is_refused(tmp_path, old, new, param):
    import shutil

    shutil.copy(EX.with_suffix(".npz"), tmp_path)
    f = tmp_path / EX.name
    text = EX.read_text()
    assert old in text
    f.write_text(text.replace(old, new, 1))
    with pytest.raises(InputError) as e:
        load_frf_model(f)
    assert e.value.param == param, e.value


def test_memory_is_estimated_before_allocating(tmp_path, monkeypatch):
    import workbench.limits
    from workbench.hbm.core.fourier import Fourier, memory_estimate

    assert memory_estimate((0, 1, 2, 3), 1 << 16, 10, 2) > memory_estimate((0, 1, 2, 3), 64, 10, 2)
    monkeypatch.setattr(workbench.limits, "available_memory", lambda: 10_000_000)
    with pytest.raises(InputError, match="fit in memory") as e:
        load_frf_model(EX, {"hbm": {"nt": 1 << 16, "harmonics": list(range(200))}})
    assert e.value.param == "hbm.nt"
    with pytest.raises(InputError, match="fit in memory"):
        Fourier((0, 1, 2, 3), 1 << 20)
    assert Fourier((0, 1, 2, 3), 64).nt == 64  # small grids are not refused


@pytest.mark.parametrize(
    "lam, says, never",
    [
        ([1.662e6, 4e18], "ill-conditioned", "singular"),
        ([1.0, 1e13], "ill-conditioned", "singular"),
        ([1e-9, 1e10], "singular", "ill-conditioned"),
        ([-1e-8, 1e10], "singular", "ill-conditioned"),
    ],
)
def test_a_positive_lowest_eigenvalue_is_never_called_singular(lam, says, never):
    from workbench.errors import SolveError
    from workbench.hbm.core.linear import check_regular

    with pytest.raises(SolveError) as e:
        check_regular(np.array(lam))
    assert says in str(e.value) and f"is {never}" not in str(e.value)
    if says == "ill-conditioned":
        assert "kt-line" in str(e.value) and "kt_n_per_m" in str(e.value)
    check_regular(np.array([1.0, 1e11]))  # a spread the solver resolves


# -- class 6: inputs that were accepted silently ----------------------------------------------


@pytest.mark.parametrize(
    "dofs, extra, needle",
    [
        ("[[0, -1, 0]]", "", "t1 and n are the same direction"),
        ("[[0, 0, 1]]", "", "t1 and t2 are the same direction"),
        ("[[0, 1, 1]]", "", "t2 and n are the same direction"),
        ("[[0, -1, 1]]", "other = [[0, -1, 1]]", "the node is against itself"),
        ("[[0, -1, 1]]", "other = [[-1, -1, 1]]", "along n is zero"),
        ("[[0, -1, 1]]", "other = [[1, -1, 0]]", "t1 and n are the same direction"),
        ("[[0, 0, 1]]", "frames = [[[1.0, 0, 0], [0, 1.0, 0], [1.0, 0, 0]]]", "orthonormal"),
        ("[[0, 0, 1]]", "frames = [[[0.5, 0, 0], [0, 1.0, 0], [0, 0, 1.0]]]", "orthonormal"),
    ],
)
def test_a_degenerate_contact_element_is_refused(tmp_path, dofs, extra, needle):
    import shutil

    src = ROOT / "studies" / "examples" / "two_dof_contact.toml"
    shutil.copy(src.with_suffix(".npz"), tmp_path)
    f = tmp_path / src.name
    f.write_text(src.read_text().replace("dofs = [[0, -1, 1]]", f"dofs = {dofs}\n{extra}", 1))
    with pytest.raises(InputError, match=needle) as e:
        load_frf_model(f)
    assert e.value.param.startswith("contact[0]."), e.value


def _study_option_argv(o) -> list[str]:
    return [f"--{o.name}"] if o.kind == "bool" else [f"--{o.name}", "1"]


def _model_refused():
    from workbench.studies.engine.spec import OPTIONS

    return [o for o in OPTIONS if o.name not in ("harmonics", "nt")]


@pytest.mark.parametrize("o", _model_refused(), ids=lambda o: o.name)
def test_nlmodes_refuses_a_study_option_with_a_model_file(tmp_path, monkeypatch, o):
    line = refused(["nlmodes", str(EX), *_study_option_argv(o)], tmp_path, monkeypatch)
    assert f"no --{o.name} with a model file" in line, line


@pytest.mark.parametrize(
    "args", [["--mode", "999"], ["--compare"], ["--levels", "1"], ["--band", "1,2"],
             ["--amplitudes", "1,2"]], ids=lambda a: a[0],
)  # fmt: skip
def test_nlmodes_refuses_a_model_option_with_a_study_file(tmp_path, monkeypatch, args):
    line = refused(["nlmodes", str(TINY), *args], tmp_path, monkeypatch)
    assert f"no {args[0]} with a study file" in line, line


@pytest.mark.parametrize("command", ["frf", "nlmodes"])
@pytest.mark.parametrize(
    "old, new, flag, value, param",
    [
        ("nt = 128", "nt = -5", "--nt", "64", "hbm.nt"),
        ("levels = [0.2, 0.5, 1.0, 2.0]", "levels = [-1.0]", "--levels", "1", "excitation.levels"),
        ("start_hz = 80.0", "start_hz = -80.0", "--band", "80,170", "band.start_hz"),
        ("end_hz = 170.0", 'end_hz = "x"', "--band", "80,170", "band.end_hz"),
        ("harmonics = [0, 1, 2, 3, 4, 5, 6, 7]", "harmonics = [0, -1]", "--harmonics", "0,1,2",
         "hbm.harmonics"),
    ],
)  # fmt: skip
def test_a_model_file_value_is_checked_although_the_command_line_overrides_it(
    tmp_path, monkeypatch, command, old, new, flag, value, param
):
    import shutil

    shutil.copy(EX.with_suffix(".npz"), tmp_path)
    (tmp_path / "m.toml").write_text(EX.read_text().replace(old, new, 1))
    line = refused([command, "m.toml", flag, value, "--out", "o"], tmp_path, monkeypatch)
    assert param in line and "although the command line overrides it" in line, line


@pytest.mark.parametrize("kind", ["comparison", "sweep", "fidelity", "robustness"])
@pytest.mark.parametrize(
    "option, value",
    [("uq-mu", "gauss 0.5 0.1"), ("uq-cf", "normal 1 0.5"), ("uq-kt", "normal 1 1"),
     ("uq-kn", "uniform 0 2"), ("uq-damping", "uniform 0.1 0.9"), ("uq-seat-tilt", "uniform -9 9"),
     ("levels-harmonics", "9-2"), ("uq-samples", "12")],
)  # fmt: skip
def test_an_option_the_study_kind_does_not_use_is_checked_all_the_same(kind, option, value):
    from workbench.studies.engine.spec import resolve

    extra = {"sweep": "mu", "sweep-values": [0.3]} if kind == "sweep" else {}
    with pytest.raises(InputError) as e:
        resolve({"kind": kind, option: value, **extra})
    assert e.value.param.startswith(option), e.value


@pytest.mark.parametrize("text", ["", "# a comment only\n"])
@pytest.mark.parametrize("command", ["frf", "nlmodes", "study", "screen"])
def test_an_empty_file_is_refused_not_taken_for_the_defaults(tmp_path, monkeypatch, command, text):
    (tmp_path / "f.toml").write_text(text)
    line = refused([command, "f.toml", "--out", "o"], tmp_path, monkeypatch)
    assert "it is empty" in line, line


@pytest.mark.parametrize("manifest", ["{}", '{"title": "x"}', '{"sections": []}'])
def test_a_manifest_without_a_study_in_it_gets_no_report(tmp_path, monkeypatch, manifest):
    (tmp_path / "r").mkdir()
    (tmp_path / "r" / "manifest.json").write_text(manifest)
    assert "it has no" in refused(["report", "r"], tmp_path, monkeypatch)
    assert not (tmp_path / "r" / "report.html").exists()


# -- class 7: names that are not UTF-8 ---------------------------------------------------------

FF = "\udcff"  # the byte 0xff of a file name, as Python keeps it


def _path_arguments() -> list[tuple[str, list[str]]]:
    """(id, argv) giving each path argument of each command a name that is not UTF-8."""
    out = []
    for command in COMMANDS:
        out.append((f"{command} --out", ["--out", f"o{FF}"]))
    for command in ("frf", "nlmodes", "study", "screen"):
        out.append((f"{command} FILE", [command, f"f{FF}.toml"]))
    out.append(("report DIR", ["report", f"r{FF}"]))
    out.append(("report --screenshot", ["report", "r", "--screenshot", f"s{FF}.png"]))
    for command in ("mesh", "modes", "reduce", "study", "screen", "nlmodes", "disk"):
        out.append((f"{command} --geometry", ["--geometry", f"g{FF}.toml"]))
    for command in ("study", "screen", "nlmodes"):  # the fidelity study's production model
        out.append((f"{command} --production-geometry", ["--production-geometry", f"p{FF}.toml"]))
    for command in ("modes", "reduce", "disk"):
        out.append((f"{command} --contact-file", ["--contact-file", f"c{FF}.toml"]))
    out.append(("disk --disk-file", ["--disk-file", f"d{FF}.toml"]))
    return out


@pytest.mark.parametrize("label, args", _path_arguments(), ids=[i for i, _ in _path_arguments()])
def test_a_name_that_is_not_utf8_is_refused_naming_it(tmp_path, monkeypatch, label, args):
    command, what = label.split()
    if what in ("FILE", "DIR") or label == "report --screenshot":
        argv = args
        (tmp_path / args[1]).write_text("x = 1\n") if what == "FILE" else None
    else:
        argv = [*_argv(command, tmp_path), *args]
    line = refused(argv, tmp_path, monkeypatch)
    assert "\\xff" in line and "UTF-8" in line, line


def test_every_path_argument_is_covered():
    """The list above holds every argument of type Path (or DIR) of every command."""
    from workbench.cli.main import build_parser

    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    have = {label for label, _ in _path_arguments()}
    for command, p in sub.choices.items():
        for a in p._actions:
            if a.type is Path or a.dest == "out" or a.metavar in ("FILE", "DIR"):
                name = a.option_strings[-1] if a.option_strings else (a.metavar or a.dest)
                name = {"model": "FILE"}.get(name, name)
                assert f"{command} {name}" in have, (command, name)


# -- the help states every range ----------------------------------------------------------------


def test_the_help_states_the_range_of_every_numeric_option():
    from workbench.cli.main import build_parser
    from workbench.studies.engine.spec import OPTIONS, range_text

    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    study = {f"--{o.name}": o for o in OPTIONS}
    for command, p in sub.choices.items():
        for a in p._actions:
            flag = a.option_strings[-1] if a.option_strings else ""
            if hasattr(a, "value"):
                assert a.value.describe(a.metavar) in a.help, (command, flag)
            elif (
                command in ("study", "screen", "nlmodes")
                and flag in study
                and study[flag].kind
                in (
                    "float",
                    "int",
                    "floats",
                    "ints",
                    "percent",
                )
            ):
                o = study[flag]
                assert range_text(o).replace("%%", "%") in a.help.replace("%%", "%"), flag
                if any(b is not None for b in (o.lo, o.hi, o.soft_lo, o.soft_hi)):
                    assert "<" in a.help, (command, flag)
            elif flag in ("--size", "--beta", "--cone-angle", "--r1", "--length"):
                assert "<" in a.help or ">" in a.help, (command, flag, a.help)

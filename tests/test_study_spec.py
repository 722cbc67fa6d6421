"""Study files and command-line options: one name per option, strict keys, precedence."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.conftest import ROOT, run_upd
from workbench.errors import InputError
from workbench.studies.engine.plan import plan
from workbench.studies.engine.spec import OPTIONS, load_study, resolve


def test_cli_overrides_file_and_records_origin(tmp_path):
    f = tmp_path / "s.toml"
    f.write_text('forces = [1.0, 2.0]\nmu = 0.4\ndampers = ["cone"]\n')
    spec = load_study(f, {"mu": "0.3"})
    assert spec.forces == [1.0, 2.0] and spec.law["mu"] == 0.3 and spec.dampers == ["cone"]
    assert spec.source["mu"] == "command line" and spec.source["forces"] == str(f)
    assert spec.source["harmonics"] == "default"


@pytest.mark.parametrize(
    "values, needle",
    [
        ({"forcs": [1.0]}, "did you mean 'forces'"),
        ({"mesh_size": 3.0}, "did you mean 'mesh-size'"),
        ({"mu": "abc"}, "mu = 'abc'"),
        ({"mu": 3.0}, "0 <= mu <= 2"),
        ({"dampers": "cone,wedgee"}, "did you mean 'wedge'"),
        ({"harmonics": [0, 2, 3]}, "containing 1"),
        ({"forces": [-1.0]}, "forces[0] = -1.0"),
        ({"band-in-phase": [420.0, 380.0]}, "lo < hi"),
        ({"sweep": "cff", "sweep-values": [1.0]}, "did you mean 'cf'"),
    ],
)
def test_bad_values_name_the_option(values, needle):
    with pytest.raises(InputError) as e:
        resolve(values)
    assert needle in str(e.value)


def test_every_option_has_a_cli_flag():
    r = run_upd("study", "--help")
    assert r.code == 0
    for o in OPTIONS:
        assert f"--{o.name}" in r.out, o.name


def test_cli_refuses_unknown_study_key_in_one_line(tmp_path):
    f = tmp_path / "bad.toml"
    f.write_text("dampers = ['cone']\nforcez = [1.0]\n")
    r = run_upd("study", f, "--out", tmp_path / "o")
    assert r.code == 2 and r.err.count("\n") == 1 and "forcez" in r.err and "forces" in r.err


def test_paper_study_plans_42_cases_with_distinct_cache_keys():
    spec = load_study(ROOT / "studies" / "paper.toml")
    cases = plan(spec)
    assert len(cases) == 3 * 2 * 7
    assert len({c.digest for c in cases}) == 42
    # cases of one damper share one model (one meshing and one reduction)
    assert len({c.model_digest for c in cases}) == 3


def test_sweep_plans_one_case_per_value_and_changes_only_the_model_key():
    spec = resolve(
        {
            "kind": "sweep",
            "sweep": "cf",
            "sweep-values": [100.0, 300.0],
            "dampers": ["cone"],
            "phases": [0.0],
            "forces": [9.6],
        }
    )
    cases = plan(spec)
    assert [c.settings["cf"] for c in cases] == [100.0, 300.0]
    assert cases[0].model_digest != cases[1].model_digest
    assert cases[0].variant == "cf=100"


def _case_studies() -> list:
    """Shipped study files whose cases plan() lays out (comparisons and sweeps).

    The fidelity and robustness studies plan their own cases and are tested
    in their own files; other TOML files in studies/ are geometry overrides.
    """
    import tomllib

    return [
        p
        for p in sorted((ROOT / "studies").glob("*.toml"))
        if tomllib.loads(p.read_text()).get("kind", "") in ("comparison", "sweep")
    ]


def test_the_shipped_case_studies_are_found():
    names = {p.name for p in _case_studies()}
    assert {"paper.toml", "cf_sweep.toml", "cone_angle_sweep.toml"} <= names


@pytest.mark.parametrize("path", _case_studies(), ids=lambda p: p.name)
def test_shipped_study_files_load_and_every_case_fits_the_groove(path):
    """Each study file we ship is valid, and every planned geometry passes the layout checks.

    make_layout runs the same fit checks as meshing (damper inside the groove,
    clear of the blades) without gmsh, so a sweep value that cannot be built
    is caught here rather than minutes into a run.
    """
    from workbench.geometry.layout import make_layout
    from workbench.geometry.params import load_geometry_params
    from workbench.pipeline import geometry_request

    spec = load_study(path)
    cases = plan(spec)
    assert cases, path.name
    seen = set()
    for c in cases:
        req = geometry_request(c)
        key = repr(req)
        if key in seen:
            continue
        seen.add(key)
        gp = load_geometry_params(
            req["damper"], req["geometry_file"], req["overrides"], req["size_mm"]
        )
        make_layout(gp)


def _sources_read(monkeypatch) -> tuple[set, Path]:
    """(the set every source file digested from now on is added to, the package folder)."""
    import workbench.io as wio

    read: set = set()
    real = wio.file_digest

    def spy(path, n=16):
        read.add(Path(path).resolve())
        return real(path, n)

    monkeypatch.setattr(wio, "file_digest", spy)
    return read, Path(wio.__file__).resolve().parents[1]


def test_the_case_key_covers_every_source_that_shapes_a_curve(monkeypatch):
    """Every source file of the contact laws (a sub-package), the harmonic balance (but
    the nonlinear modes), the branch's HDF5 writer, the assembly and the model pipeline
    is read into a case's cache key: editing any of them recomputes the cases."""
    from workbench.studies.engine.plan import NLMODE_PACKAGE, solver_code_version

    read, pkg = _sources_read(monkeypatch)
    solver_code_version()
    want = {pkg / "io" / "record.py"} | {
        p.resolve()
        for d in ("contact", "hbm", "assembly", "pipeline")
        for p in (pkg / d).rglob("*.py")
        if not (d == "hbm" and p.relative_to(pkg / d).parts[0] == NLMODE_PACKAGE)
    }
    assert any(p.parent.name == "laws" for p in want)  # the sub-package is there to miss
    assert not want - read, sorted(str(p.relative_to(pkg)) for p in want - read)


def test_the_case_key_covers_the_mesher_and_the_reduction(monkeypatch):
    """The sources that make a case's model (the mesher's, the reduction's, the pads')
    are read into its model key and so into its cache key: a change to them recomputes
    the cases, not only the meshes and reduced models."""
    import workbench.studies.engine.plan as plan_mod
    from workbench.studies.engine.plan import make_case, model_code_version

    read, pkg = _sources_read(monkeypatch)
    model_code_version()
    for f in ("geometry/occ.py", "geometry/mirror.py", "geometry/shapes/cone.py",
              "fe/pads.py", "fe/craig_bampton.py", "fe/reduce.py"):  # fmt: skip
        assert pkg / f in read, f
    # a bladed-disk case's key: its sector's digest has the mesher's; the FE package's
    # sources (the cyclic reduction, the pads) and the solver's come in here
    from workbench.studies.engine.plan import disk_code_version

    read.clear()
    disk_code_version()
    for f in ("fe/cyclic.py", "fe/cyclic_cb.py", "fe/pads.py", "hbm/core/fourier.py"):
        assert pkg / f in read, f
    from workbench.studies.engine.spec import load_study

    settings = load_study(None, {}).as_dict()
    before = make_case("cone", 0.0, 30.0, settings)
    monkeypatch.setattr(plan_mod, "_MODEL_CODE", lambda: "another model code")
    after = make_case("cone", 0.0, 30.0, settings)
    assert after.model_digest != before.model_digest and after.digest != before.digest


def test_code_version_counts_sub_packages(tmp_path):
    from workbench.io import code_version

    (tmp_path / "sub").mkdir()
    (tmp_path / "a.py").write_text("A = 1\n")
    (tmp_path / "sub" / "b.py").write_text("B = 1\n")
    v0 = code_version(tmp_path)
    (tmp_path / "sub" / "b.py").write_text("B = 2\n")
    assert code_version(tmp_path) != v0


def test_the_spec_is_a_dataclass_with_each_option_in_one_place():
    """Shared options are fields of the spec, a kind's own are fields of its record
    (``spec.<kind>``), a contact law's parameters ``spec.law``; the file and the command
    line still name them flat, and ``as_dict``/``replace`` see every one."""
    import dataclasses

    from workbench.studies.engine.spec import StudySpec
    from workbench.studies.kinds.fidelity.options import FidelityOptions
    from workbench.study_options import SharedOptions

    names = {f.name for f in dataclasses.fields(StudySpec)}
    assert {"forces", "mesh_size", "law", "kinds"} <= names and "levels_nt" not in names
    assert issubclass(StudySpec, SharedOptions)
    spec = resolve({"kind": "fidelity", "levels-nt": [16, 32], "mu": 0.3}, "f.toml")
    assert isinstance(spec.fidelity, FidelityOptions) and spec.fidelity.levels_nt == [16, 32]
    assert spec.law == {"mu": 0.3} and spec.source["levels-nt"] == "f.toml"
    assert list(spec.as_dict()) == [o.name for o in OPTIONS]
    assert spec.as_dict()["levels-nt"] == [16, 32] and spec.as_dict()["mu"] == 0.3
    other = spec.replace(levels_nt=[8], mu=0.2, forces=[1.0])
    assert (other.fidelity.levels_nt, other.law["mu"], other.forces) == ([8], 0.2, [1.0])
    assert spec.fidelity.levels_nt == [16, 32]  # the original is unchanged
    with pytest.raises(AttributeError):
        _ = spec.no_such_kind

"""Study files and command-line options: one name per option, strict keys, precedence."""

from __future__ import annotations

import pytest

from tests.conftest import ROOT, run_upd
from workbench.errors import InputError
from workbench.studies.plan import plan
from workbench.studies.spec import OPTIONS, load_study, resolve


def test_cli_overrides_file_and_records_origin(tmp_path):
    f = tmp_path / "s.toml"
    f.write_text('forces = [1.0, 2.0]\nmu = 0.4\ndampers = ["cone"]\n')
    spec = load_study(f, {"mu": "0.3"})
    assert spec.forces == [1.0, 2.0] and spec.mu == 0.3 and spec.dampers == ["cone"]
    assert spec.source["mu"] == "command line" and spec.source["forces"] == str(f)
    assert spec.source["harmonics"] == "default"


@pytest.mark.parametrize("values, needle", [
    ({"forcs": [1.0]}, "did you mean 'forces'"),
    ({"mesh_size": 3.0}, "did you mean 'mesh-size'"),
    ({"mu": "abc"}, "mu = 'abc'"),
    ({"mu": 3.0}, "0 <= mu <= 2"),
    ({"dampers": "cone,wedgee"}, "did you mean 'wedge'"),
    ({"harmonics": [0, 2, 3]}, "containing 1"),
    ({"forces": [-1.0]}, "forces[0] = -1.0"),
    ({"band-in-phase": [420.0, 380.0]}, "lo < hi"),
    ({"sweep": "cff", "sweep-values": [1.0]}, "did you mean 'cf'"),
])
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
    spec = resolve({"kind": "sweep", "sweep": "cf", "sweep-values": [100.0, 300.0],
                    "dampers": ["cone"], "phases": [0.0], "forces": [9.6]})
    cases = plan(spec)
    assert [c.settings["cf"] for c in cases] == [100.0, 300.0]
    assert cases[0].model_digest != cases[1].model_digest
    assert cases[0].variant == "cf=100"

"""The report's Inputs: every value used (never None), with its unit and source, per study kind."""

from __future__ import annotations

from pathlib import Path

import pytest

from workbench.post.inputs import used_inputs
from workbench.render.report import render_html
from workbench.studies.engine.outputs import headline
from workbench.studies.engine.spec import load_study
from workbench.studies.kinds import inputs_table

ROOT = Path(__file__).resolve().parents[1]


def _rows(path, **cli):
    s = load_study(ROOT / path, cli or None)
    # the kind's rows come from its registry entry, as the study engine passes them
    rows = used_inputs(s.as_dict(), s.source, table=inputs_table(s.kind))
    return {r["option"]: r for r in rows}


def test_comparison_shows_file_values_with_their_source():
    rows = _rows("studies/paper.toml", mu=0.4)
    assert all(r["value"] is not None for r in rows.values())
    # unset: the contact and geometry files' values, named
    assert rows["cf"]["value"] == 10000.0 and rows["cf"]["unit"] == "N"
    assert rows["cf"]["source"] == "default: geometry/contact.toml [contact]"
    assert rows["kt-line"]["value"] == 6e10 and rows["kt-line"]["unit"] == "N/m per m"
    assert rows["mesh-size"]["value"] == 9.0 and "rig.toml" in rows["mesh-size"]["source"]
    assert rows["nt"]["value"] == 64 and "solver default" in rows["nt"]["source"]
    # given: the value and where
    assert rows["mu"]["value"] == 0.4 and rows["mu"]["source"] == "command line"
    assert rows["modes"]["source"] == "studies/paper.toml"
    # only what a comparison uses
    for other in (
        "levels-modes",
        "methods",
        "hard-cases",
        "tolerance",
        "sweep-values",
        "knobs",
        "peak-tolerance",
    ):
        assert other not in rows


def test_sweep_names_the_swept_values_and_wedge_only_face_stiffness():
    rows = _rows("studies/cf_sweep.toml", dampers="wedge")
    assert rows["cf"]["value"][0] == 500.0 and rows["cf"]["source"].startswith("swept")
    assert "kt-face" in rows and "kt-line" not in rows and "cone-angle" not in rows


@pytest.mark.parametrize(
    "path, kept, dropped",
    [
        ("studies/fidelity.toml", "levels-modes", "methods"),
        ("studies/robustness.toml", "hard-cases", "levels-modes"),
        ("tests/studies/uncertainty_tiny.toml", "uq-samples", "hard-cases"),
    ],
)
def test_other_kinds_list_their_own_options(path, kept, dropped):
    rows = _rows(path)
    assert kept in rows and dropped not in rows
    assert all(r["value"] is not None for r in rows.values())
    assert not any(str(r["value"]).startswith("/") for r in rows.values())  # paths relative


def test_units_come_from_the_option_declarations():
    """Each row's unit is its option's declared unit (shared or the kind's own)."""
    rows = _rows("studies/fidelity.toml")
    assert rows["levels-nt"]["unit"] == "samples per period" and rows["modes"]["unit"] == "per body"
    assert rows["damping"]["unit"] == "ratio" and rows["phases"]["unit"] == "deg"
    assert _rows("studies/robustness.toml")["peak-tolerance"]["unit"] == "%"


def test_report_table_has_unit_and_source(tmp_path):
    s = load_study(ROOT / "studies/paper.toml")
    html = render_html({"title": "t", "inputs_used": used_inputs(s.as_dict(), s.source)}, tmp_path)
    assert "<th>unit</th>" in html and "<td>N/m per m</td>" in html
    assert "<td>None</td>" not in html and "default: geometry/contact.toml [contact]" in html


def test_a_geometry_files_contact_table_is_the_contact_shown():
    """Resolved without a solve (older manifests): the paper-like rig's own [contact]
    table, not geometry/contact.toml (issue 33: the report stated mu 0.5 and CF 10 kN)."""
    rows = _rows("studies/paper_rig.toml")
    assert rows["mu"]["value"] == 0.3 and rows["cf"]["value"] == 13600.0
    assert rows["kt-line"]["value"] == 4.0e10 and rows["kn-face"]["value"] == 9.15e11
    assert rows["mu"]["source"] == "default: geometry/paper_rig.toml [contact]"


def test_sweep_headline_names_the_case():
    from tests.synthetic import synthetic_sweep

    lines = headline(synthetic_sweep("cf", (500.0, 1000.0, 5000.0)))
    assert lines and all("=" in line.split(":")[0] for line in lines), lines

"""The inputs a report, results.h5 and summary.json state are those the solve used (issue 33).

The contact of a rig calibrated with its own ``[contact]`` table (here a
temporary copy of geometry/paper_rig.toml with another mu and CF) must be
the contact every output names, with its unit and its file. The fast test
runs the real chain from the file to the outputs: the runner's
``contact_params_for``, the assembly's preload, the record the runner's
``solve_case`` makes (``post.provenance.solve_inputs``) and the study's
``write_outputs``; only the FE models and the curves are stand-ins (a
synthetic branch). The slow test runs a whole small study.
"""

from __future__ import annotations

import json
import math
import re
import shutil
from pathlib import Path
from types import SimpleNamespace

import h5py
import numpy as np
import pytest

from tests.conftest import ROOT, run_upd
from tests.synthetic import contact_layout, synthetic_case

MU, CF = 0.27, 12345.0  # not the file's 0.3 and 13600 N, nor geometry/contact.toml's 0.5, 10 kN


def _geometry_copy(tmp_path: Path, mu: float = MU, cf: float = CF) -> Path:
    text = (ROOT / "geometry" / "paper_rig.toml").read_text()
    text, n_mu = re.subn(r"(?m)^mu = 0\.3$", f"mu = {mu}", text)
    text, n_cf = re.subn(r"(?m)^cf_n = 13600\.0$", f"cf_n = {cf}", text)
    assert n_mu == n_cf == 1, "geometry/paper_rig.toml's [contact] table changed: update the test"
    p = tmp_path / "my_rig.toml"
    p.write_text(text)
    return p


def _prepared(case, contact_params):
    """What ``prepare_model`` hands ``solve_case``, with a synthetic contact layout in place
    of the FE models: the contact parameters of the runner, the geometry parameters of the
    file, the assembly's preload and pair stiffnesses."""
    from workbench.assembly.model import preloads
    from workbench.geometry.params import load_geometry_params
    from workbench.geometry.records import ContactSet

    gp = load_geometry_params(case.damper, case.settings.get("geometry"))
    params = gp.as_dict()
    beta = float(params["rig"]["platform"]["angle_deg"])
    pts, side, _ = contact_layout(case.damper)
    n = len(pts)
    contact = ContactSet(pts, np.tile(np.eye(3), (n, 1, 1)), side, np.full(n, 2.3e-3), "line")
    kt, kn = contact_params.pair_stiffness("line", contact.weight)
    assembled = SimpleNamespace(
        contact=contact,
        n0=preloads(contact, contact_params.cf_n, contact_params.mu, beta),
        kt=kt,
        kn=kn,
        mu=np.full(n, contact_params.mu),
        n_pairs=n,
        n=300,
    )
    geometry = SimpleNamespace(damper=case.damper, params=params, digest="stand-in")
    system = SimpleNamespace(zeta=case.settings["damping"], C=None, contacts=None)
    return SimpleNamespace(
        contact_params=contact_params, geometry=geometry, assembled=assembled, system=system
    )


def _study(tmp_path: Path, geo: Path):
    from workbench.hbm.core.options import SolverOptions
    from workbench.pipeline import contact_params_for
    from workbench.post.provenance import solve_inputs
    from workbench.post.results import StudyResults
    from workbench.studies.engine.plan import plan
    from workbench.studies.engine.spec import load_study

    spec = load_study(
        ROOT / "studies" / "paper_rig.toml",
        {"dampers": "cone", "phases": "0", "forces": "9.6,30", "geometry": str(geo)},
    )
    cases = []
    for c in plan(spec):
        prep = _prepared(c, contact_params_for(c))
        r = synthetic_case(c.damper, c.phase_deg, c.force_n)
        r.digest = c.digest
        r.inputs = solve_inputs(prep, c.settings, r.branch, SolverOptions(max_points=400))
        cases.append(r)
    return spec, StudyResults(spec.name, spec.kind, cases, inputs=spec.as_dict())


def test_a_changed_contact_in_the_geometry_file_reaches_every_output(tmp_path):
    from workbench.studies.engine.outputs import write_outputs

    geo = _geometry_copy(tmp_path)
    spec, results = _study(tmp_path, geo)
    out = tmp_path / "study"
    write_outputs(results, spec, out, {})

    # results.h5: every case's inputs, each with its unit and where it came from
    with h5py.File(out / "results.h5", "r") as h:
        for c in results.cases:
            g = h[f"cases/{c.case_id}/case/inputs"]
            assert g["mu"][()] == pytest.approx(MU) and g["mu"].attrs["unit"] == "1"
            assert g["cf"][()] == pytest.approx(CF) and g["cf"].attrs["unit"] == "N"
            assert g["cf"].attrs["source"].endswith("my_rig.toml [contact]")
            assert g["kt_line"][()] == pytest.approx(4.0e10)  # unchanged, from the copy too
            side = CF / (2 * (math.sin(math.radians(30)) + MU * math.cos(math.radians(30))))
            assert g["preload_per_side"][()] == pytest.approx(side, rel=1e-12)
            assert g["preload_per_side"].attrs["unit"] == "N"
            assert g["slip_limit_per_side"][()] == pytest.approx(MU * side, rel=1e-12)
            assert g["nt"][()] == 64 and g["harmonics"][()].tolist() == [0, 1, 2, 3]
            for name, d in g.items():
                if isinstance(d, h5py.Dataset):
                    assert "unit" in d.attrs and "source" in d.attrs, name

    # summary.json: the same, per case
    rows = json.loads((out / "summary.json").read_text())
    assert len(rows) == 2
    for row in rows:
        assert row["inputs"]["mu"]["value"] == pytest.approx(MU)
        assert row["inputs"]["cf"] == {
            "value": CF,
            "unit": "N",
            "source": row["inputs"]["cf"]["source"],
            "label": "centrifugal load on the damper",
            "group": "contact",
        }
        assert row["inputs"]["cf"]["source"].endswith("my_rig.toml [contact]")
        assert row["inputs"]["mesh_size"]["unit"] == "mm"

    # the report's Inputs table: the file's values, with the file named
    html = (out / "report.html").read_text()
    inputs = html[html.index("<h2 id='inputs'>") :]
    assert "<td>friction coefficient (mu)</td><td>0.27</td>" in inputs
    assert "<td>centrifugal load on the damper (cf)</td><td>12345</td><td>N</td>" in inputs
    assert inputs.count("my_rig.toml [contact]") == 4  # mu, cf, kt and kn of the lines
    # neither the repository's paper-like rig values nor the heavy rig's defaults
    assert "<td>13600</td>" not in inputs and "<td>10000</td>" not in inputs
    assert "geometry/contact.toml" not in inputs


def test_the_record_follows_the_file_it_was_given(tmp_path):
    """Two files, two records: the values come from the objects each solve was given."""
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    _, a = _study(tmp_path, _geometry_copy(tmp_path / "a"))
    _, b = _study(tmp_path, _geometry_copy(tmp_path / "b", mu=0.35, cf=9000.0))
    assert a.cases[0].inputs["mu"]["value"] == pytest.approx(MU)
    assert b.cases[0].inputs["mu"]["value"] == pytest.approx(0.35)
    assert b.cases[0].inputs["cf"]["value"] == pytest.approx(9000.0)
    assert a.cases[0].inputs["preload_per_side"]["value"] != pytest.approx(
        b.cases[0].inputs["preload_per_side"]["value"]
    )


@pytest.mark.slow
def test_a_whole_study_states_the_geometry_files_contact(tmp_path):
    """The tiny study (cone, 14 mm) on a rig file whose [contact] table differs from
    geometry/contact.toml: the report, results.h5 and summary.json name its values."""
    geo = tmp_path / "rig_with_contact.toml"
    contact = (ROOT / "geometry" / "contact.toml").read_text()
    contact = re.sub(r"(?m)^mu = 0\.5$", f"mu = {MU}", contact)
    contact = re.sub(r"(?m)^cf_n = 10000\.0$", f"cf_n = {CF}", contact)
    assert f"mu = {MU}" in contact and f"cf_n = {CF}" in contact
    geo.write_text(contact)
    out = tmp_path / "tiny"
    shutil.copy(ROOT / "tests" / "studies" / "tiny.toml", tmp_path / "tiny.toml")
    r = run_upd("study", tmp_path / "tiny.toml", "--geometry", geo, "--forces", "30", "--out", out)
    assert r.code == 0, r
    rows = json.loads((out / "summary.json").read_text())
    assert rows[0]["inputs"]["mu"]["value"] == pytest.approx(MU)
    assert rows[0]["inputs"]["cf"]["source"].endswith("rig_with_contact.toml [contact]")
    with h5py.File(out / "results.h5", "r") as h:
        (cid,) = list(h["cases"])
        assert h[f"cases/{cid}/case/inputs/cf"][()] == pytest.approx(CF)
    html = (out / "report.html").read_text()
    assert "<td>friction coefficient (mu)</td><td>0.27</td>" in html

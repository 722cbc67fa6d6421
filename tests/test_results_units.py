"""results.h5 and reduced-model files: a unit on every numeric dataset (docs/RESULTS.md)."""

from __future__ import annotations

import re
from pathlib import Path

import h5py
import numpy as np
import pytest

from tests.synthetic import synthetic_study
from workbench.reduced import ReducedModel

DOC = Path(__file__).resolve().parents[1] / "docs" / "RESULTS.md"


def _datasets(h):
    out = {}

    def visit(name, obj):  # returns None: h5py's visititems stops at the first non-None
        if isinstance(obj, h5py.Dataset):
            out[name] = obj

    h.visititems(visit)
    return out


def test_every_results_dataset_has_a_documented_unit(tmp_path):
    from tests.test_report_provenance import _geometry_copy, _study

    study = synthetic_study()
    # a case as the runner writes it: with the inputs its solve used (case/inputs/...)
    study.cases[0].inputs = _study(tmp_path, _geometry_copy(tmp_path))[1].cases[0].inputs
    assert study.cases[0].inputs
    p = study.save(tmp_path / "results.h5")
    doc = DOC.read_text()
    with h5py.File(p, "r") as h:
        ds = _datasets(h)
        assert ds
        assert any("/case/inputs/" in name for name in ds)
        for name, d in ds.items():
            assert "unit" in d.attrs, name
            leaf = name.split("/", 2)[2]  # cases/<case id>/<leaf>
            if leaf.startswith("case/inputs/shape/"):  # one line for every shape parameter
                leaf = "case/inputs/shape/<parameter>"
            assert f"`{leaf}`" in doc, f"{leaf} is not in docs/RESULTS.md"
        cid = study.cases[0].case_id
        assert h[f"cases/{cid}/friction_energy"].attrs["unit"] == "J"
        assert h[f"cases/{cid}/freq_hz"].attrs["unit"] == "Hz"
        assert h[f"cases/{cid}/case/points"].attrs["unit"] == "m"
    # the attributes do not change what is read back
    again = type(study).load(p)
    np.testing.assert_array_equal(again.cases[0].energy_mj, study.cases[0].energy_mj)


def test_reduced_model_units(tmp_path):
    rm = ReducedModel(
        name="rig",
        kind="user",
        K=np.eye(3) * 1e4,
        M=np.eye(3),
        T=np.eye(3),
        node_coords=np.zeros((1, 3)),
        node_sets={"contact": np.array([0])},
    )
    p = rm.save(tmp_path / "rig.h5")
    doc = DOC.read_text()
    with h5py.File(p, "r") as h:
        for name, d in _datasets(h).items():
            if name.startswith("node_sets/"):
                continue  # index arrays
            assert "unit" in d.attrs, name
            assert re.search(rf"`{name}`", doc), name
        assert h["K"].attrs["unit"] == "N/m" and h["M"].attrs["unit"] == "kg"
    np.testing.assert_array_equal(ReducedModel.load(p).K, rm.K)


def test_a_negative_loop_integral_is_reported_as_zero_with_its_value():
    """Dissipation cannot be negative: a sampled loop that hardly opens can sum to a small
    negative number; the summary reports 0 and says what was computed."""
    from tests.synthetic import synthetic_case

    case = synthetic_case("wedge", 0.0, 9.6)
    i = case.peak_index
    e = case.branch.friction_energy
    e[i] = 0.0
    e[i, 0] = -1.0e-6  # J: -1e-3 mJ, the value once seen on a wedge at 9.6 N
    s = case.summary()
    assert s["friction_energy_mj"] == 0.0
    assert "-1.00e-03 mJ" in s["friction_energy_note"]
    e[i, 0] = 2.0e-6
    s = case.summary()
    assert s["friction_energy_mj"] == pytest.approx(2.0e-3) and s["friction_energy_note"] == ""

"""The mistuned bladed disk from the tuned cyclic sector (issue 32, items 1 and 2).

A coarse 6-blade disk of the paper-like rig's section with the cylinder damper
(tests/test_sector_hbm.py's): 6 fixed-interface modes per ND, 4 for the damper.
Mistuning is a Young's modulus deviation ``delta_j`` per sector (the whole sector:
the mesh does not tag the blade), projected on the tuned cyclic Craig-Bampton
basis (:mod:`workbench.pipeline.mistuning`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from workbench.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
PAPER = ROOT / "geometry" / "paper_rig.toml"
COARSE = {
    "rig": {"mesh": {"size_mm": 25.0, "contact_size_mm": 8.0, "damper_size_mm": 10.0}},
    "cylinder": {"n_contact_points": 3},
}
N = 6


def _contact():
    from workbench.assembly.params import load_contact_params

    return load_contact_params(geometry_file=PAPER)


@pytest.fixture(scope="module")
def disk(tmp_path_factory):
    from workbench.geometry.disk_build import build_disk_sector
    from workbench.pipeline.mistuning import build_mistuning_model

    rec = build_disk_sector(
        "cylinder", tmp_path_factory.mktemp("mist6"), geometry_file=PAPER, n_blades=N,
        overrides=COARSE,
    )  # fmt: skip
    return rec, build_mistuning_model(rec, _contact(), n_modes=6, n_damper_modes=4)


@pytest.mark.parametrize("eo", [0, 1, 2, 3])
def test_zero_mistuning_is_the_tuned_full_disk(disk, eo):
    """Zero deviations: the mistuned system is full_disk_system's, bit for bit; blade 0's
    output row is full_disk_system's sector-0 row. A uniform deviation delta projects onto
    delta times the tuned sector stiffness (the cross-ND sums over sectors vanish)."""
    from workbench.pipeline.mistuning import mistuned_disk_system, stiffness_deviation
    from workbench.pipeline.sector import full_disk_system

    _, mm = disk
    s0, f0, o0 = full_disk_system(mm.model, eo)
    s1, f1, o1 = mistuned_disk_system(mm, np.zeros(N), eo)
    assert np.array_equal(s0.K, s1.K) and np.array_equal(s0.M, s1.M)
    assert np.array_equal(s0.C, s1.C) and np.array_equal(f0, f1)
    assert (s0.contacts.W != s1.contacts.W).nnz == 0
    assert o1.shape == (N, s0.K.shape[0]) and np.array_equal(o1[0], o0[0])
    n = mm.n_sector_dofs
    dK = stiffness_deviation(mm, np.full(N, 0.03))
    assert np.abs(dK - 0.03 * s0.K[:n, :n]).max() < 1e-12 * np.abs(dK).max()


def test_bad_deviations_are_one_line_errors():
    from workbench.pipeline.mistuning import check_deviations, whitehead_bound

    assert check_deviations([0.01, -0.02, 0.0], 3).tolist() == [0.01, -0.02, 0.0]
    bad = (
        ([0.0, -1.0, 0.0], "deviations[1]"),
        ([0.0, -1.5, 0.0], "deviations[1]"),
        ([0.0, 0.0], "deviations"),
        ([0.0, float("nan"), 0.0], "deviations[1]"),
        ("x", "deviations"),
    )
    for dev, param in bad:
        with pytest.raises(InputError) as e:
            check_deviations(dev, 3)
        assert e.value.param == param and "\n" not in str(e.value), str(e.value)
    assert "1 + delta" in str(pytest.raises(InputError, check_deviations, [-2, 0, 0], 3).value)
    assert whitehead_bound(4) == 1.5 and abs(whitehead_bound(6) - 1.7247449) < 1e-7

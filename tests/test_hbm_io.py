"""Branch files, curve comparison, and the TOML model input of ``upd frf``."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from workbench.errors import InputError
from workbench.hbm import Branch, curve_distance, frequency_response, load_frf_model
from workbench.hbm.io.examples import sdof_jenkins, two_dof_contact, write_example_files

EXAMPLES = Path(__file__).resolve().parents[1] / "studies" / "examples"


def test_branch_round_trip(tmp_path):
    ex = two_dof_contact()
    b = frequency_response(
        ex.system, ex.f1, 2.0, ex.band_hz, ex.outputs, output_names=("x", "z"), label="two dof"
    )
    p = b.save(tmp_path / "b.h5")
    c = Branch.load(p)
    for name in (
        "freq_hz",
        "stable",
        "stability",
        "stability_how",
        "status",
        "friction_energy",
        "x",
        "out_amp",
        "out_harm",
        "energy_residual",
        "work_ext",
    ):
        np.testing.assert_array_equal(getattr(b, name), getattr(c, name))
    assert c.output_names == ("x", "z") and c.label == "two dof" and c.completed
    assert c.summary()["peak_frequency_hz"] == b.summary()["peak_frequency_hz"]
    csv = b.to_csv(tmp_path / "b.csv", unit_scale=1e3, unit="mm").read_text().splitlines()
    head = "freq_hz,stable,stability,stability_how,newton_its,energy_residual,accuracy,x_amp_mm"
    assert csv[0].startswith(head)
    words = {line.split(",")[2] for line in csv[1:]}
    verdicts = {"stable", "unstable", "unknown", "stable (carried)", "unstable (carried)"}
    assert words <= verdicts and words
    hows = [line.split(",")[3] for line in csv[1:]]
    assert set(hows) <= {"none", "hill", "linear", "carried"}
    # a carried verdict says so in both columns, and is never "stable" in the first
    for line in csv[1:]:
        c = line.split(",")
        assert (c[3] == "carried") == c[2].endswith("(carried)")
        assert c[1] == str(int(c[2] == "stable"))
    assert len(csv) == b.n_points + 1
    assert not list(tmp_path.glob(".*part"))  # atomic writes leave no temporary file


def test_curve_distance_ignores_sampling_and_sees_shape():
    f = np.linspace(0, 1, 41)
    a = 1 / np.sqrt((1 - (f * 2) ** 2) ** 2 + 0.01)
    fine = np.linspace(0, 1, 2001)
    af = 1 / np.sqrt((1 - (fine * 2) ** 2) ** 2 + 0.01)
    d = curve_distance(f, a, fine, af)
    assert d < 2e-2  # chord sagitta of the coarse polyline only
    assert curve_distance(f, a, f[::-1], a[::-1]) == 0.0  # order does not matter
    assert curve_distance(f, a, f, 1.2 * a) > 0.1
    assert curve_distance(f, a, fine, af) == curve_distance(fine, af, f, a)


def test_example_matrices_are_the_documented_models(tmp_path):
    """studies/examples/*.npz are what write_example_files makes (and the TOML reads them)."""
    for p in write_example_files(tmp_path):
        with np.load(p) as new, np.load(EXAMPLES / p.name) as old:
            for k in ("M", "K"):
                np.testing.assert_allclose(new[k], old[k], rtol=1e-15)
    m = load_frf_model(EXAMPLES / "sdof_jenkins.toml")
    ref = sdof_jenkins()
    np.testing.assert_allclose(m.system.K, ref.system.K)
    np.testing.assert_allclose(m.system.contacts.W.toarray(), ref.system.contacts.W.toarray())
    assert m.system.contacts.kt1[0] == pytest.approx(ref.system.contacts.kt1[0])
    m2 = load_frf_model(EXAMPLES / "two_dof_contact.toml")
    ref2 = two_dof_contact()
    np.testing.assert_allclose(m2.system.contacts.W.toarray(), ref2.system.contacts.W.toarray())
    assert m2.levels == ref2.levels and m2.band_hz == ref2.band_hz


def _write(tmp_path: Path, text: str, **arrays) -> Path:
    np.savez(tmp_path / "m.npz", **arrays)
    p = tmp_path / "m.toml"
    p.write_text(text)
    return p


BASE = """
[model]
matrices = "m.npz"
damping_ratio = 0.01
[excitation]
dofs = [0]
amplitudes_n = [1.0]
levels = [1.0]
[band]
start_hz = 10.0
end_hz = 20.0
[output]
dofs = [1]
[[contact]]
dofs = [[0, -1, 1]]
other = [[2, -1, -1]]
mu = 0.3
kt_n_per_m = 1e4
kn_n_per_m = 1e4
n0_n = 1.0
"""


def test_model_file_with_sparse_and_hdf5_matrices(tmp_path):
    import h5py
    import scipy.sparse as sp

    K = np.array([[2e4, -1e4, 0], [-1e4, 2e4, -1e4], [0, -1e4, 2e4]])
    M = np.eye(3) * 0.1
    Ks = sp.csr_matrix(K)
    p = _write(
        tmp_path,
        BASE,
        M=M,
        K_data=Ks.data,
        K_indices=Ks.indices,
        K_indptr=Ks.indptr,
        K_shape=np.array(Ks.shape),
    )
    m = load_frf_model(p)
    np.testing.assert_allclose(m.system.K, K)
    u = (m.system.contacts.W @ np.array([1.0, 2.0, 3.0])).reshape(-1, 3)
    np.testing.assert_allclose(u[0], [1.0 - 3.0, 0.0, 2.0])  # t1 relative to the platform DOF
    with h5py.File(tmp_path / "m.h5", "w") as h:
        h["mass"] = M
        h["stiff/K"] = K
    (tmp_path / "h.toml").write_text(
        BASE.replace(
            'matrices = "m.npz"', 'matrices = "m.h5"\nmass = "mass"\nstiffness = "stiff/K"'
        )
    )
    m2 = load_frf_model(tmp_path / "h.toml")
    np.testing.assert_allclose(m2.system.M, M)


@pytest.mark.parametrize(
    "edit, param",
    [
        (("mu = 0.3", "muu = 0.3"), "contact[0].muu"),
        (("dofs = [1]", "dofs = [7]"), "output.dofs[0]"),
        (("start_hz = 10.0", "start_hz = 0.0"), "band.start_hz"),
        (("end_hz = 20.0", "end_hz = 5.0"), "band.end_hz"),
        (('matrices = "m.npz"', 'matrices = "none.npz"'), "model.matrices"),
        (("levels = [1.0]", "levels = [-1.0]"), "excitation.levels[0]"),
        (("amplitudes_n = [1.0]", "amplitudes_n = [1.0, 2.0]"), "excitation.amplitudes_n"),
        (("[band]", "[bnd]"), "bnd"),
    ],
)
def test_model_file_errors_name_the_key(tmp_path, edit, param):
    K = np.eye(3) * 1e4
    p = _write(tmp_path, BASE.replace(*edit), M=np.eye(3), K=K)
    with pytest.raises(InputError) as e:
        load_frf_model(p)
    assert e.value.param == param


def test_branch_without_verdicts_loads_as_stable_or_unstable(tmp_path):
    """A file written before the three-valued verdict (no 'stability' dataset) still loads."""
    import h5py

    ex = two_dof_contact()
    b = frequency_response(ex.system, ex.f1, 1.0, (150, 160), ex.outputs, harmonics=(0, 1, 2))
    p = b.save(tmp_path / "b.h5")
    with h5py.File(p, "a") as h:
        del h["stability"]
    c = Branch.load(p)
    np.testing.assert_array_equal(c.stability, b.stable.astype(np.int8))

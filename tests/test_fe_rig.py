"""The FE stage on a small complete rig (two blades, base, block damper).

The rig comes from :func:`workbench.fe.samples.toy_rig` so that these tests
do not depend on the real geometry builders (tests/test_fe_defaults.py runs
the real rig, marked slow). Checked here:

* the reduced rig + damper with stuck contacts reproduce the unreduced FE
  model's first six frequencies within 0.1 % (issue 4, item 6), from above;
* the rigid damper gives the same frequencies where the damper is stiff;
* the first bending pair is recognised from the shapes, with the physics
  of a damper that only couples the blades out of phase;
* reduced models are cached by digest, saved with their contact frames,
  rebuilt when an input changes.
"""

from __future__ import annotations

import logging

import numpy as np
import pytest
import scipy.linalg as sl

from workbench.assembly.params import load_contact_params
from workbench.errors import InputError
from workbench.fe.coupling import pair_springs, stuck_reduced_system
from workbench.fe.modes import classify_bending, compute_modes
from workbench.fe.reduce import cached_model, load_contact, reduce_body
from workbench.fe.samples import toy_rig
from workbench.reduced import ReducedModel

N = 8
# The toy rig's own contact stiffness (not geometry/contact.toml, which is tuned
# for the real rig): soft enough that the block damper's modes on its springs
# sit among the blade modes, the hard case for a reduction.
PARAMS = load_contact_params(
    kt_line_n_per_m2=2.7e7, kn_line_n_per_m2=2.7e7, kt_face_n_per_m3=2.7e9, kn_face_n_per_m3=2.7e9
)


def hz(K, M, n=N):
    return np.sqrt(np.maximum(sl.eigh(K, M, eigvals_only=True, subset_by_index=[0, n - 1]), 0)) / (
        2 * np.pi
    )


@pytest.fixture(scope="module")
def rig(tmp_path_factory):
    out = tmp_path_factory.mktemp("toy")
    geom = toy_rig(out / "geometry", lc=0.004)
    stuck = compute_modes(geom, contact="stuck", n=N, contact_params=PARAMS, out_dir=out / "modes")
    cache = out / "cache"
    models = {
        "rig": reduce_body(geom, "rig", cache_dir=cache),
        "damper": reduce_body(geom, "damper", cache_dir=cache),
        "rigid": reduce_body(geom, "damper", rigid=True, cache_dir=cache),
    }
    return geom, stuck, models, cache


def test_reduced_stuck_system_matches_full_fe(rig):
    """First 6 stuck frequencies of the CB models within 0.1 % of the full FE, from above."""
    geom, stuck, m, _ = rig
    K, M = stuck_reduced_system(m["rig"], m["damper"], geom.contact, PARAMS)
    f = hz(K, M)
    rel = f / stuck.freqs_hz - 1
    assert np.all(rel[:6] < 1e-3), rel
    assert np.all(rel > -1e-8), rel  # Rayleigh-Ritz: a reduced model is stiffer


def test_rigid_damper_matches_flexible(rig):
    """Rigid vs Craig-Bampton damper: within 0.1 % for the first 6 stuck modes.

    The block damper's first free-free elastic mode is near 47 kHz, while its
    contact springs hold it at a few hundred Hz, so its deformation energy
    is of the order (f / 47 kHz)^2: a few 1e-4 at most.
    """
    geom, _, m, _ = rig
    f_cb = hz(*stuck_reduced_system(m["rig"], m["damper"], geom.contact, PARAMS))
    f_rigid = hz(*stuck_reduced_system(m["rig"], m["rigid"], geom.contact, PARAMS))
    assert np.allclose(f_rigid[:6], f_cb[:6], rtol=1e-3, atol=0)
    assert m["rigid"].kind == "rigid" and m["rigid"].n == 6
    assert m["rigid"].M[0, 0] == pytest.approx(geom.damper_mass_kg, rel=1e-9)
    assert np.allclose(m["rigid"].ref_point, geom.damper_centroid, atol=1e-12)


def test_first_bending_pair_is_recognised(rig):
    """Stuck: the in-phase and out-of-phase first bending modes are found.

    The toy damper sits between the blades' inner faces: out of phase the
    blades squeeze it through the normal springs (stiffer than the free
    blades), in phase it rides along (its mass lowers the frequency).
    """
    geom, stuck, _, _ = rig
    free = compute_modes(geom, contact="free", n=4, contact_params=PARAMS, shapes=False)
    assert stuck.in_phase is not None and stuck.out_of_phase is not None
    f_in, f_out = stuck.freqs_hz[stuck.in_phase], stuck.freqs_hz[stuck.out_of_phase]
    f_free = free.freqs_hz[0]
    assert f_in < f_free < f_out
    u = stuck.response_disp
    assert u[stuck.in_phase, 0, 0] * u[stuck.in_phase, 1, 0] > 0
    assert u[stuck.out_of_phase, 0, 0] * u[stuck.out_of_phase, 1, 0] < 0
    # in phase the damper translates with the blades; out of phase, squeezed from both
    # sides, it hardly moves: its share of the modal mass tells the two apart
    share = stuck.damper_share
    assert np.all((share >= 0) & (share <= 1 + 1e-9))
    assert share[stuck.in_phase] > 10 * share[stuck.out_of_phase]
    assert np.all(free.damper_share == 0)
    # free: the damper is off; its own free-free spectrum starts with 6 elastic modes
    assert len(free.damper_freqs_hz) == 6 and free.damper_freqs_hz[0] > 1e4
    assert free.labels[0].startswith("first bending")


def test_classify_bending_rules():
    """Hand-made shapes: in-phase, out-of-phase, single blade, second bending, torsion."""
    x = np.array([1.0, 0, 0])
    shapes = np.array(
        [
            [0.1 * np.array([0, 1, 0]), 0.1 * np.array([0, 1, 0])],  # y motion: not bending in x
            [x, x * 0.9],  # in-phase
            [x, -x],  # out-of-phase
            [x, 0.01 * x],  # blade 1 alone
            [x, x],  # in-phase, but the excitation point moves the other way: 2nd bending
        ]
    )
    exc = 0.3 * shapes.copy()
    exc[4] *= -1
    labels, i_in, i_out = classify_bending(shapes, exc)
    assert (i_in, i_out) == (1, 2)
    assert labels[0] == "" and labels[3] == "first bending, blade 1 alone"
    assert labels[4] == "bending in x in-phase"


def test_springs_follow_the_frames(rig):
    """S_i = R^T diag(kt, kt, kn) R: n^T S n = kn, t^T S t = kt, symmetric."""
    geom, _, _, _ = rig
    S = pair_springs(geom.contact, PARAMS)
    kt, kn = PARAMS.pair_stiffness(geom.contact.kind, geom.contact.weight)
    R = geom.contact.frames
    assert np.allclose(np.einsum("ni,nij,nj->n", R[:, 2], S, R[:, 2]), kn)
    assert np.allclose(np.einsum("ni,nij,nj->n", R[:, 0], S, R[:, 0]), kt)
    assert np.allclose(S, np.transpose(S, (0, 2, 1)))


def test_reduced_models_contract(rig):
    """Interface order, node sets, T, check(); the HDF5 holds the contact frames."""
    geom, _, m, cache = rig
    r, d = m["rig"], m["damper"]
    n_p = geom.contact.n_pairs
    assert r.kind == "craig-bampton" and r.n == 3 * r.n_nodes + 12
    assert np.array_equal(r.node_sets["contact"], np.arange(n_p))
    assert np.array_equal(r.node_sets["excitation"], [n_p, n_p + 1])
    assert np.array_equal(r.node_sets["response"], [n_p + 2, n_p + 3])
    assert np.allclose(r.node_coords[:n_p], geom.contact.points)
    assert np.allclose(r.node_coords[r.node_sets["response"]], geom.response_points)
    assert np.array_equal(d.node_sets["contact"], np.arange(n_p))
    assert np.allclose(r.T, np.hstack([np.eye(3 * r.n_nodes), np.zeros((3 * r.n_nodes, 12))]))
    for rm in m.values():
        rm.check()
        assert rm.code_version and rm.digest and rm.inputs["geometry_digest"] == geom.digest
    path = cached_model(geom, "rig", cache_dir=cache)
    back = ReducedModel.load(path)
    assert np.array_equal(back.K, r.K) and back.digest == r.digest
    cs = load_contact(path)
    assert np.allclose(cs.frames, geom.contact.frames) and cs.kind == geom.contact.kind


def test_cache_reused_and_rebuilt(rig, caplog):
    """Unchanged inputs: read back (logged); other options: a new model."""
    geom, _, m, cache = rig
    with caplog.at_level(logging.INFO, logger="workbench.fe"):
        again = reduce_body(geom, "damper", cache_dir=cache)
    assert "reusing" in caplog.text
    assert np.array_equal(again.M, m["damper"].M)
    assert cached_model(geom, "damper", n_modes=4, cache_dir=cache) is None
    fewer = reduce_body(geom, "damper", n_modes=4, cache_dir=cache)
    assert fewer.n == m["damper"].n - 8 and fewer.digest != m["damper"].digest
    assert cached_model(geom, "damper", n_modes=4, cache_dir=cache) is not None


def test_bad_options_are_input_errors(rig):
    geom, _, _, cache = rig
    with pytest.raises(InputError, match="n_modes"):
        reduce_body(geom, "rig", n_modes=-1, cache_dir=cache)
    with pytest.raises(InputError, match="rigid"):
        reduce_body(geom, "rig", rigid=True, cache_dir=cache)
    with pytest.raises(InputError, match="body"):
        reduce_body(geom, "blade", cache_dir=cache)
    with pytest.raises(InputError, match="contact"):
        compute_modes(geom, contact="slip")


def test_mode_shapes_written(rig):
    """XDMF files exist; mode-shape pictures are not blank."""
    from conftest import assert_nonblank

    from workbench.render.modes import render_modes

    geom, stuck, _, _ = rig
    for key in ("modes_rig_xdmf", "modes_damper_xdmf"):
        text = open(stuck.files[key]).read()
        assert text.count("<Time Value=") == N
    out = stuck.files["modes_rig_xdmf"].rsplit("/", 1)[0]
    pngs = render_modes(stuck, out, modes=[stuck.in_phase])
    assert [p.name for p in pngs] == [f"mode_{stuck.in_phase + 1:02d}.png", "first_bending.png"]
    for p in pngs:
        assert_nonblank(p)

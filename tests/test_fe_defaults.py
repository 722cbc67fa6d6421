"""The default rig and dampers (geometry/*.toml, contact.toml): slow, full meshes.

* item 7 of issue 4: with the damper stuck, the out-of-phase first bending
  lies between 350 and 450 Hz (the paper's is about 409 Hz) for every damper;
* item 6: the Craig-Bampton rig + damper (12 modes each) reproduce the
  first six stuck frequencies of the unreduced FE model within 0.1 %, and
  the rigid damper agrees with the flexible one where the damper is stiff
  compared with its contacts.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sl

from workbench.assembly.params import load_contact_params
from workbench.fe.coupling import stuck_reduced_system
from workbench.fe.modes import compute_modes
from workbench.fe.reduce import reduce_body
from workbench.geometry import build_geometry

pytestmark = pytest.mark.slow
PARAMS = load_contact_params()


@pytest.mark.parametrize("damper", ["cone", "cylinder", "wedge"])
def test_stuck_out_of_phase_near_the_papers(tmp_path, damper):
    geom = build_geometry(damper, tmp_path / "geometry")
    res = compute_modes(geom, contact="stuck", n=6, contact_params=PARAMS, shapes=False)
    assert res.in_phase is not None and res.out_of_phase is not None
    f_out = res.freqs_hz[res.out_of_phase]
    assert 350.0 <= f_out <= 450.0, res.summary()


def test_reduced_and_rigid_match_full_on_the_default_cone_rig(tmp_path):
    """First 6 stuck frequencies: CB within 0.1 % of full FE (from above); rigid damper.

    The rigid damper must agree where the damper is stiff *relative to its
    contacts*. With soft contact springs (2.7e7 N/m per m of line, 1e6 N/m a
    line; the damper's first free-free elastic mode is near 42 kHz) it is
    within 0.1 % of the flexible one. With the default, Hertz-level stiffness
    (6e10 N/m per m, 2.4e9 N/m a line) the damper's own compliance is of the
    order of its contacts' and the rigid damper is stiffer: by Rayleigh's
    principle never softer than the flexible one (4.9 % on the out-of-phase
    mode when this was written), which the fidelity study charts.
    """
    geom = build_geometry("cone", tmp_path / "geometry")
    soft = load_contact_params(kt_line_n_per_m2=2.7e7, kn_line_n_per_m2=2.7e7)
    rig = reduce_body(geom, "rig", cache_dir=tmp_path / "fe")
    dampers = {
        r: reduce_body(geom, "damper", rigid=r, cache_dir=tmp_path / "fe") for r in (False, True)
    }

    def reduced_hz(params, rigid):
        K, M = stuck_reduced_system(rig, dampers[rigid], geom.contact, params)
        return np.sqrt(sl.eigh(K, M, eigvals_only=True, subset_by_index=[0, 5])) / (2 * np.pi)

    for params in (PARAMS, soft):
        full = compute_modes(geom, contact="stuck", n=6, contact_params=params, shapes=False)
        rel_cb = reduced_hz(params, False) / full.freqs_hz - 1
        assert np.all(rel_cb < 1e-3) and np.all(rel_cb > -1e-8), rel_cb
    assert np.allclose(reduced_hz(soft, True), reduced_hz(soft, False), rtol=1e-3, atol=0)
    assert np.all(reduced_hz(PARAMS, True) >= reduced_hz(PARAMS, False) * (1 - 1e-9))

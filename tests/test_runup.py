"""The run-up integrator (workbench.hbm.timedomain.runup) against the dense reference.

The condensed Newmark step (contact DOFs by Woodbury) is the same scheme as
workbench.hbm.timedomain.timeint, so from the same rest state and step size both must
reach the same periodic response: on the two-DOF 3-D contact example (normal
load variation and partial separation) the harmonic-1 amplitudes agree to the
Newton tolerances, not to a discretisation error. A continued run equals an
uninterrupted one, and a ramped start reaches the same steady state when
the orbit is unique (the contact slips every period).
"""

from __future__ import annotations

import numpy as np
import pytest

from workbench.errors import InputError
from workbench.hbm.core.fourier import Fourier
from workbench.hbm.io.examples import two_dof_contact
from workbench.hbm.timedomain.runup import runup
from workbench.hbm.timedomain.timeint import time_response


@pytest.fixture(scope="module")
def ex():
    return two_dof_contact(zeta=0.02)


def test_runup_reaches_the_dense_reference(ex):
    f = 140.0
    tr = time_response(
        ex.system, ex.f1, 4.0, f, [0, 1], harmonics=(0, 1), steps_per_period=256, tol=1e-10
    )
    ru = runup(ex.system, ex.f1, 4.0, f, [0, 1], periods=tr.periods, steps_per_period=256)
    h1_ref = tr.h1_amplitude
    assert np.all(np.abs(ru.h1[-1] / h1_ref - 1) < 1e-6), (ru.h1[-1], h1_ref)
    four = Fourier((0, 1), 256)
    assert np.allclose(ru.mean[-1], tr.harmonics[four.index(0, "0")], rtol=1e-6, atol=1e-12)
    # the amplitude builds up from rest
    assert ru.h1[0, 0] < 0.8 * ru.h1[-1, 0]


def test_a_continued_runup_equals_one_run(ex):
    one = runup(ex.system, ex.f1, 4.0, 140.0, [0], periods=12, steps_per_period=64)
    a = runup(ex.system, ex.f1, 4.0, 140.0, [0], periods=5, steps_per_period=64)
    b = runup(ex.system, ex.f1, 4.0, 140.0, [0], periods=7, steps_per_period=64, start=a.state)
    assert np.array_equal(np.concatenate([a.h1, b.h1]), one.h1)
    assert np.array_equal(b.state["q"], one.state["q"])


def test_a_ramped_start_reaches_the_same_slipping_orbit(ex):
    sudden = runup(ex.system, ex.f1, 4.0, 140.0, [0], periods=150, steps_per_period=128)
    ramped = runup(
        ex.system, ex.f1, 4.0, 140.0, [0], periods=150, steps_per_period=128, ramp_periods=20
    )
    assert sudden.slip_samples[-1] > 0
    assert abs(ramped.h1[-1, 0] / sudden.h1[-1, 0] - 1) < 1e-6


def test_bad_input_names_the_parameter(ex):
    with pytest.raises(InputError, match="periods"):
        runup(ex.system, ex.f1, 1.0, 140.0, periods=0)
    with pytest.raises(InputError, match="freq_hz"):
        runup(ex.system, ex.f1, 1.0, -5.0)

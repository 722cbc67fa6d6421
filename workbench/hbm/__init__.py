"""Multi-harmonic balance with 3-D friction contact: AFT, SNES corrector, continuation, Hill.

Works on matrices only (numpy, scipy, numba, petsc4py imported lazily);
imports neither dolfinx nor gmsh, so any reduced model can be used.

The contract
------------
Contact elements (:class:`workbench.contact.ContactElements`): a sparse
``W`` (``3 n_el x n``) from the generalised coordinates ``q`` to each
element's local relative displacement ``[t1, t2, n]`` (damper minus
platform; ``n > 0`` opens), per element ``mu``, ``kt1``, ``kt2``, ``kn``,
``n0`` (N, compressive positive) and the law ("decoupled" Jenkins pair, as
in "On the efficiency of a conical under-platform damper for turbines", or
"circular", or any law of :mod:`workbench.contact.laws`) with its own
parameters per element (``law_params``; its ``step`` reads them as ``lp``).
Single-direction elements and elements against the ground
are the same record with zero rows / no platform columns. The force on
``q`` is ``W^T f`` with ``f = [T1, T2, -N]``.

System (:class:`System`): ``M``, ``K`` and ``C`` (dense or sparse) or
modal damping ratios ``zeta`` (see :func:`modal_damping`: on the modes of
the system with stuck contacts, so a free-free damper is fine), the
contacts, a static force, and ``balance=True`` which adds the constant
force making ``u = 0`` the static equilibrium (the preloads carry the
centrifugal load). The solver regularises ``K`` with the stuck contact
stiffness, ``K + W^T K_c W``, and subtracts ``K_c u`` from the contact
force; a state where the closed contacts stop holding a free body is
reported as "the damper has lost contact", not solved.

Excitation: ``f(t) = level * Re(f1 exp(i w t))`` with ``f1`` complex per
DOF (phases per DOF: an inter-blade phase angle); outputs: DOF indices or
an observation matrix.

:func:`frequency_response` ``(system, f1, level, band_hz, outputs,
harmonics=(0, 1, 2, 3), nt=None, options=SolverOptions(), ...) -> Branch``.
The :class:`Branch` holds per point the frequency (Hz), the Hill stability
flag, Newton iterations, the energy-balance residual, the output amplitude
(max over the period of ``|y(t)|``) and harmonic-1 amplitude, the status of
each element (0 stuck, 1 stick-slip, 2 partial separation, 3 full
separation), the friction energy per element per cycle (J), the solved
unknowns (every DOF follows from ``HarmonicBalance.response``), plus
``completed``/``failed``, ``message`` and timings; ``save``/``load``
(HDF5, atomic). A failed solve never raises: the branch says so and keeps
its points.

:func:`time_response` is the time-integration reference (Newmark, same
law) at chosen frequencies; :func:`curve_distance` compares curves by
nearest point in normalised arc length; :func:`load_frf_model` reads the
TOML input of ``upd frf``.

Fourier layout: :mod:`workbench.hbm.core.fourier` (the one place that defines
it). Sub-packages: ``core`` (Fourier layout, AFT, the system record, linear
receptances, the balance's residual, Jacobian, recovery and energies,
options), ``path`` (the one path-following engine: protocol, step rule,
loop, Newton), ``forced`` (the forced response, its correctors, peaks, the
Branch record), ``stability`` (Hill's method, verdicts along a branch),
``nlmodes`` (backbones of nonlinear modes, synthesis), ``timedomain`` (the
time-integration references), ``io`` (the model file, examples, the HDF5
record writer).
"""

from .core.balance import HarmonicBalance
from .core.fourier import Fourier
from .core.options import SolverOptions
from .core.system import System, modal_damping
from .forced.branch import Branch, curve_distance
from .forced.response import frequency_response
from .io.modelfile import FrfModel, load_frf_model
from .timedomain.timeint import TimeResponse, time_response

__all__ = [
    "Branch",
    "Fourier",
    "FrfModel",
    "HarmonicBalance",
    "SolverOptions",
    "System",
    "TimeResponse",
    "curve_distance",
    "frequency_response",
    "load_frf_model",
    "modal_damping",
    "time_response",
]

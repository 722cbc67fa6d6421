"""Options of the corrector, the continuation and the stability analysis (one small record)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from ...config import param, validate


@dataclass(frozen=True)
class SolverOptions:
    """How a frequency response is computed. Every field is a TOML key of ``[solver]``.

    The defaults are the robust choice: analytic Jacobian, Newton with
    backtracking line search, pseudo-arc-length continuation with a secant
    predictor, an adaptive step, and Hill's method at every point.
    """

    # corrector (PETSc SNES)
    jacobian: str = param(
        "analytic", "analytic Jacobian or PETSc finite differences", choices=("analytic", "fd")
    )
    linear_solver: str = param(
        "auto",
        "newton: fresh LU every iteration; lagged: GMRES preconditioned by the last LU, "
        "refreshed when GMRES slows; chord: the last LU alone; auto: newton for small systems",
        choices=("auto", "newton", "lagged", "chord"),
    )
    line_search: str = param("bt", "SNES line search type", choices=("basic", "bt", "l2", "cp"))
    line_search_max_it: int = param(
        2,
        "trial step lengths of the bt line search per Newton iteration (PETSc's own default "
        "is 40; more only creep along a kink, where a shorter continuation step is cheaper)",
        lo=1,
        hi=100,
    )
    max_newton: int = param(25, "Newton iterations per point", lo=1, hi=1000)
    tol: float = param(
        1e-10,
        "converged when |r|_inf <= tol * max(|x|_inf, u_ref) (relative)",
        lo=0.0,
        lo_open=True,
        hi=1e-2,
    )
    tol_stall: float = param(
        1e-7,
        "accepted when Newton stalls on a kink of the residual (stick/slip transition) "
        "below this relative residual",
        lo=0.0,
        lo_open=True,
        hi=1e-2,
    )
    stagnation: int = param(
        8,
        "give up a corrector solve whose residual has not halved in this many Newton "
        "iterations (a step across a kink: the continuation halves it; 0: never)",
        lo=0,
        hi=1000,
    )
    ksp_rtol: float = param(
        1e-10, "relative tolerance of GMRES (lagged)", lo=0.0, lo_open=True, hi=0.5
    )
    ksp_max_it: int = param(40, "GMRES iterations per Newton step (lagged)", lo=1, hi=1000)
    refresh_ksp_its: int = param(20, "refresh the LU when GMRES needed this many iterations", lo=1)
    factor_precision: str = param(
        "auto",
        "precision of the LU (single halves its time; GMRES and refinement restore "
        "double accuracy); auto: single above single_above unknowns in lagged mode",
        choices=("auto", "double", "single"),
    )
    single_above: int = param(2000, "auto: unknowns above which the LU is single precision", lo=0)
    reduce_factor: bool = param(True, "factor only the columns of elements that are not stuck")
    compiled: str = param(
        "auto",
        "auto: the compiled corrector for small systems with modal damping (the same steps "
        "as PETSc's, one compiled call per solve); off: always PETSc SNES",
        choices=("auto", "off"),
    )
    auto_newton_limit: int = param(
        200, "auto: unknowns up to which every iteration refactors", lo=0
    )
    # continuation
    continuation: str = param(
        "arclength",
        "pseudo-arc-length or plain frequency stepping",
        choices=("arclength", "frequency"),
    )
    predictor: str = param("secant", "predictor", choices=("secant", "tangent", "constant"))
    ds0: float = param(0.01, "first step (normalised arc length)", lo=0.0, lo_open=True, hi=1.0)
    ds_min: float = param(1e-5, "smallest step before giving up", lo=0.0, lo_open=True, hi=1.0)
    ds_max: float = param(0.2, "largest step (normalised arc length)", lo=0.0, lo_open=True, hi=1.0)
    dc_weight: float = param(
        0.0, "weight of the mean (harmonic 0) unknowns in the arc length", lo=0.0, hi=1.0
    )
    target_newton: int = param(6, "Newton iterations the step size aims at", lo=1, hi=100)
    max_angle_deg: float = param(
        25.0, "largest turn between successive secants, deg", lo=1.0, hi=90.0
    )
    max_correction: float = param(
        0.5,
        "largest corrector move off the predictor, relative to the step (else halve)",
        lo=0.0,
        lo_open=True,
    )
    max_points: int = param(3000, "points per curve before stopping", lo=2)
    refine_peak: bool = param(
        True,
        "bracketed search (Brent) of the max |y(t)| peak and of the harmonic-1 peak, each at "
        "its own frequency",
    )
    peak_iterations: int = param(
        30, "largest number of trials of each peak's bracketed (Brent) search", lo=1, hi=100
    )
    peak_ftol: float = param(
        1e-4,
        "each peak search stops when its frequency bracket is narrower than this (relative)",
        lo=0.0,
        lo_open=True,
        hi=0.1,
    )
    # stability
    stability: bool = param(
        True,
        "Hill's stability: established where it can change, carried between "
        "(workbench.hbm.stability.along_path)",
    )
    stability_stride: int = param(
        8,
        "most points between two Hill checks where some contact slips or separates (fewer "
        "where the least-damped exponent nears the axis; 1: every point)",
        lo=1,
        hi=1000,
    )
    n_floquet: int = param(6, "Floquet exponents ARPACK starts with (large systems)", lo=1, hi=200)
    n_floquet_max: int = param(
        48,
        "Floquet exponents ARPACK may grow to while covering |lambda| <= w/2 (else unknown)",
        lo=1,
        hi=2000,
    )
    hill_dense_limit: int = param(
        700, "Hill state size up to which all exponents are computed", lo=0
    )
    unstable_tol: float = param(1e-6, "unstable if max Re(lambda) > unstable_tol * w", lo=0.0)
    # formulation
    space: str = param(
        "auto",
        "unknowns: contact DOFs (condensed) or all DOFs (physical)",
        choices=("auto", "condensed", "physical"),
    )
    backend: str = param(
        "auto",
        "receptances: modal (needs modal damping) or direct (any C)",
        choices=("auto", "modal", "direct"),
    )
    dc_anchor: float = param(
        1e-3,
        "mean-position anchor of bodies held only by contacts, relative to kt (0: none)",
        lo=0.0,
        hi=1.0,
    )
    accuracy_tol: float = param(
        1e-2,
        "warn when the loop-energy vs harmonic-work mismatch exceeds this fraction of the "
        "excitation work at some point (nt or harmonics too few for the contact loops)",
        lo=0.0,
        lo_open=True,
    )
    n_fine: int = param(256, "samples per period for the peak of the output", lo=16)

    def __post_init__(self) -> None:
        validate(self)
        if self.ds_min > self.ds_max:
            from ...errors import InputError

            raise InputError("ds_min", self.ds_min, f"ds_min <= ds_max = {self.ds_max}")

    def replace(self, **kw: object) -> SolverOptions:
        return dataclasses.replace(self, **kw)

"""The robustness study's named solution methods and hard cases (plain data).

:data:`METHODS`: name -> (SolverOptions overrides, description);
:data:`CASES`: name -> :class:`HardCase` (damper, phase, force, the study
options it changes, why it is hard). The options ``methods`` and
``hard-cases`` of :mod:`workbench.study_options` list them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

# the robustness study's solution methods: name -> (SolverOptions overrides, description)
METHODS: dict[str, tuple[dict[str, Any], str]] = {
    "default": (
        {},
        "analytic Jacobian, bt line search, arc length, secant predictor, "
        "adaptive step (the options of every other study)",
    ),
    "fd-jacobian": ({"jacobian": "fd"}, "finite-difference Jacobian (dense, column by column)"),
    "ls-basic": ({"line_search": "basic"}, "full Newton steps (SNES line search basic)"),
    "ls-l2": ({"line_search": "l2"}, "SNES line search l2"),
    "ls-cp": ({"line_search": "cp"}, "SNES line search cp (critical point)"),
    "tangent-predictor": ({"predictor": "tangent"}, "tangent predictor instead of secant"),
    "constant-predictor": (
        {"predictor": "constant"},
        "constant predictor (Newton starts at the last point)",
    ),
    "fixed-step": (
        {"ds0": 0.01, "ds_min": 0.01, "ds_max": 0.01, "max_points": 3000},
        "a fixed small arc-length step 0.01, never adapted (no halving on failure; "
        "a budget of 3000 points instead of the study's max-points)",
    ),
    "frequency-stepping": (
        {"continuation": "frequency"},
        "plain frequency stepping (adaptive), no arc length",
    ),
}


@dataclass(frozen=True)
class HardCase:
    """One hard case: a damper, a phase, a force and the study options it changes."""

    damper: str
    phase_deg: float
    force_n: float
    settings: dict[str, Any]
    why: str


# the robustness study's hard cases (workbench/studies/kinds/robustness/compute.py solves them)
CASES: dict[str, HardCase] = {
    "near-separation": HardCase(
        "cone",
        0.0,
        9.6,
        {"cf": 1000.0},
        "in-phase cone, centrifugal load 1 kN (a tenth of the default): the preload N0 is "
        "small against the dynamic normal load, the pairs open for part of the period",
    ),
    "high-kt-ratio": HardCase(
        "cone",
        180.0,
        9.6,
        {"kt-line": 6.0e11, "mu": 0.1},
        "out-of-phase cone, tangential stiffness x10 and friction coefficient / 5: "
        "kt / (mu N0) is 50 times the default, the slip displacement 50 times smaller",
    ),
    "high-force": HardCase(
        "cone",
        180.0,
        60.0,
        {},
        "out-of-phase cone at 60 N, twice the paper's highest level (gross slip)",
    ),
    "wedge-in-phase": HardCase(
        "wedge",
        0.0,
        30.0,
        {},
        "in-phase wedge at 30 N: the faces separate (partly) around the peak",
    ),
    "turning-point": HardCase(
        "cone",
        0.0,
        30.0,
        {"damping": 5e-4},
        "in-phase cone at 30 N with damping 0.05 %: the curve folds (softening with "
        "separation) in a narrow frequency range, so plain frequency stepping must jump",
    ),
    "light-damping": HardCase(
        "cone",
        180.0,
        9.6,
        {"damping": 1e-4},
        "out-of-phase cone with modal damping 0.01 %: a sharp, friction-dominated peak",
    ),
}

"""The step control of the path engine: one frozen set of knobs, two presets.

The forced response and the backbone grew their own step rules; the
presets :meth:`StepRule.forced` and :meth:`StepRule.backbone` reproduce
each exactly (the pinned results of tests/test_path_pinned.py). Where the
two differ only by history (growth law, acceptance test, halving limit,
fallbacks, end handling) the difference is a knob here, to be unified in a
commit that is allowed to change results.

Modes: ``"arclength"`` (pseudo-arc-length steps from the first point on),
``"natural"`` (steps in the parameter, the last clipped to the end) and
``"hybrid"`` (steps in the parameter; where they stall, ``hybrid_arc``
pseudo-arc-length steps pass the fold, then back).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class StepRule:
    mode: str  # "arclength" | "natural" | "hybrid"
    ds0: float
    ds_min: float
    ds_max: float
    predictor: str = "secant"  # "secant" | "tangent" | "constant"
    # growth: "target" aims at target_newton iterations (sqrt law, a fresh
    # linearisation when slower); "bands" grows 1.5 at <= 4 its_scale, 0.7 above 8
    growth: str = "target"
    target_newton: int = 4
    its_scale: float = 1.0
    # acceptance: a step turning by more than max_angle_deg (in arc-length steps),
    # correcting by more than max_correction * ds, or changing the watched outputs by
    # more than max_change is halved, at most max_turns times in a row
    max_angle_deg: float = 30.0
    max_correction: float | None = None
    max_change: float | None = None
    max_turns: int = 3
    turn_is_failure: bool = False  # a halving for a turn counts as a failed step
    fallbacks: bool = False  # sphere, then reversed plane, where the plane ahead fails
    reject_backwards: bool = False  # a step against the secant is refused
    retrace_tol: float | None = None  # a point within this * ds of an older one is refused
    refresh_on_failure: bool = True  # a fresh linearisation after a failed step
    # the end: "retry" (interpolated guess, fresh linearisation, the step's own
    # solution, then smaller steps), "once" (interpolated guess; else the step past
    # it ends the path), "clip" (natural steps clipped to the end)
    end: str = "retry"
    end_inclusive: bool = False  # a step landing exactly on the end has passed it
    start_rtol: float = 0.0  # below start * (1 - start_rtol): turned back
    fold_drop: float | None = None  # arc steps falling this far below the top: stop
    fold_points: int | None = None  # this many points without a new top: stop
    close_in: float | None = None  # a lost contact further than this ahead halves the step
    max_points: int = 400
    max_solves: int | None = None
    hybrid_switch: float = 0.0  # natural steps below this: arc-length steps
    hybrid_arc: int = 8  # how many
    hybrid_ds: float = 0.0  # their first step

    @classmethod
    def forced(cls, opts, band: float) -> StepRule:
        """The forced response's rule from :class:`workbench.hbm.core.options.SolverOptions`;
        ``band``: the frequency span (natural steps are in rad/s)."""
        if opts.continuation == "arclength":
            return cls(
                mode="arclength",
                ds0=opts.ds0,
                ds_min=opts.ds_min,
                ds_max=opts.ds_max,
                predictor=opts.predictor,
                target_newton=opts.target_newton,
                max_angle_deg=opts.max_angle_deg,
                max_correction=opts.max_correction,
                fallbacks=True,
                end="retry",
                start_rtol=1e-12,
                max_points=opts.max_points,
            )
        return cls(
            mode="natural",
            ds0=opts.ds0 * band,
            ds_min=opts.ds_min * band,
            ds_max=opts.ds_max * band,
            predictor=opts.predictor,
            target_newton=opts.target_newton,
            end="clip",
            max_points=opts.max_points,
        )

    @classmethod
    def backbone(
        cls, n_steps: int, max_points: int, max_change: float, max_fold_points: int, its_scale
    ) -> StepRule:
        """The backbone's rule: steps in ln a of ``1 / n_steps`` of the range to start."""
        return cls(
            mode="hybrid",
            ds0=1.0 / n_steps,
            ds_min=1e-5,
            ds_max=2.0 / n_steps,
            growth="bands",
            its_scale=its_scale,
            max_angle_deg=30.0,
            max_change=max_change,
            max_turns=4,
            turn_is_failure=True,
            reject_backwards=True,
            retrace_tol=0.3,
            refresh_on_failure=False,
            end="once",
            end_inclusive=True,
            fold_drop=float(np.log(2.0)),
            fold_points=max_fold_points,
            close_in=float(np.log(1.02)),
            max_points=max_points,
            max_solves=5 * max_points,
            hybrid_switch=1e-3 / n_steps,
            hybrid_arc=8,
            hybrid_ds=1.0 / n_steps,
        )

    def grow(self, ds: float, its: int) -> tuple[float, bool]:
        """The next step after a point solved in ``its`` iterations, and whether the
        linearisation is to be refreshed."""
        if self.growth == "target":
            refresh = its > self.target_newton
            factor = 2.0 if its == 0 else np.clip(np.sqrt(self.target_newton / its), 0.5, 2.0)
            return float(np.clip(ds * factor, self.ds_min, self.ds_max)), refresh
        k = self.its_scale
        g = 1.5 if its <= 4 * k else (0.7 if its > 8 * k else 1.0)
        return float(np.clip(ds * g, self.ds_min, self.ds_max)), False

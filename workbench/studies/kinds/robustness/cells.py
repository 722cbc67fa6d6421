"""The robustness study's cells: one frequency response per (method, problem), classified.

A :class:`Problem` is a frequency response to compute with every method
(built lazily: it may need a rig model); :func:`run_cell` solves it with
one named method (never raising for a failed solve), :func:`classify`
judges each cell against the reference method (ok, wrong answer, failed).
:func:`workbench.studies.kinds.robustness.compute.method_map` runs, caches and classifies
the whole grid.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ....errors import InputError, SolveError
from ....hard_cases import METHODS
from ....io import digest
from .time_check import turning_points

log = logging.getLogger(__name__)


STATUSES = ("ok", "wrong", "failed")
# a point whose energy balance (work of the excitation against the dissipated work per cycle)
# is off by more than this is not a periodic solution: the branch is a wrong answer


ENERGY_TOL = 1e-4


@dataclass
class Problem:
    """A frequency response to compute with every method (built lazily, as it may need a model).

    ``build()`` returns ``(system, f1, band_hz, outputs, output_names)``; ``key``
    identifies everything that shapes the answer except the solver options.
    """

    name: str
    key: str
    level: float
    harmonics: tuple[int, ...]
    nt: int | None
    build: Callable[[], tuple[Any, np.ndarray, tuple[float, float], Any, tuple[str, ...]]]
    base_options: dict[str, Any] = field(default_factory=dict)
    info: dict[str, Any] = field(default_factory=dict)
    _built: Any = None

    def get(self):
        if self._built is None:
            self._built = self.build()
        return self._built


def method_options(name: str, base: dict[str, Any] | None = None):
    """The SolverOptions of method ``name`` (over the ``base`` fields)."""
    from ....hbm.core.options import SolverOptions

    if name not in METHODS:
        raise InputError("methods", name, "one of " + ", ".join(METHODS))
    return SolverOptions(**{**(base or {}), **METHODS[name][0]})


def _cell_key(problem: Problem, method: str) -> str:
    opts = method_options(method, problem.base_options)
    from ....config import record_to_dict
    from ...engine.plan import _SOLVER_CODE

    return digest(
        {
            "problem": problem.key,
            "method": method,
            "options": record_to_dict(opts),
            "code": _SOLVER_CODE(),
        }
    )


def run_cell(problem: Problem, method: str) -> dict[str, Any]:
    """Solve ``problem`` with ``method``; never raises for a failed solve."""
    from ....hbm.forced.response import frequency_response

    opts = method_options(method, problem.base_options)
    system, f1, band, outputs, names = problem.get()
    t0 = time.perf_counter()
    branch, error = None, ""
    try:
        branch = frequency_response(
            system,
            f1,
            problem.level,
            band,
            outputs=outputs,
            harmonics=problem.harmonics,
            nt=problem.nt,
            options=opts,
            output_names=names,
            label=f"{problem.name} / {method}",
        )
    except (SolveError, RuntimeError, ArithmeticError, np.linalg.LinAlgError) as e:
        # a method that crashes has failed: say how, do not stop the study
        log.warning("%s / %s raised %s: %s", problem.name, method, type(e).__name__, e)
        error = f"raised {type(e).__name__}: {e}"
    wall = time.perf_counter() - t0
    rec: dict[str, Any] = {
        "case": problem.name,
        "method": method,
        "wall_s": wall,
        "band_hz": [float(band[0]), float(band[1])],
    }
    if branch is None:
        rec.update(
            failed=True,
            completed=False,
            message=error,
            n_points=0,
            newton_its=0,
            freq_hz=[],
            amp=[],
            stable=[],
            stability=[],
        )
    else:
        s = branch.summary()
        rec.update(
            failed=bool(branch.failed),
            completed=bool(branch.completed),
            message=branch.message,
            n_points=branch.n_points,
            newton_its=int(s["newton_its"]),
            energy_residual_max=s["energy_residual_max"],
            n_unknowns=int(branch.stats.get("n_unknowns", 0)),
            n_snes_failed=int(branch.stats.get("n_failed", 0)),
            freq_hz=branch.freq_hz.tolist(),
            amp=branch.out_amp[:, 0].tolist() if branch.n_points else [],
            stable=branch.stable.tolist(),
            stability=branch.stability.astype(int).tolist(),
            max_status=int(branch.status.max()) if branch.status.size else 0,
            separated_share=float(np.mean(branch.status >= 2)) if branch.status.size else 0.0,
        )
    return _describe(rec)


def _describe(rec: dict[str, Any]) -> dict[str, Any]:
    f = np.asarray(rec["freq_hz"], dtype=float)
    a = np.asarray(rec["amp"], dtype=float)
    lo, hi = rec["band_hz"]
    rec["freq_reached_hz"] = float(f.max()) if f.size else None
    rec["band_fraction"] = float((f.max() - lo) / (hi - lo)) if f.size else 0.0
    rec["last_freq_hz"] = float(f[-1]) if f.size else None
    i = int(np.argmax(a)) if a.size else -1
    rec["peak_amplitude"] = float(a[i]) if i >= 0 else None
    rec["peak_frequency_hz"] = float(f[i]) if i >= 0 else None
    tp = turning_points(f)
    rec["n_turning_points"] = int(tp.size)
    rec["turning_points_hz"] = [round(float(f[j]), 4) for j in tp]
    v = np.asarray(rec["stability"], dtype=int)  # Hill's: 1, 0, -1 (unknown), 2/3 carried
    rec["n_unstable"] = int(np.sum(v == 0))
    rec["n_unstable_carried"] = int(np.sum(v == 3))
    rec["n_stability_unknown"] = int(np.sum(v < 0))
    rec["succeeded"] = bool(not rec["failed"] and rec["completed"])
    return rec


def classify(cells: list[dict[str, Any]], reference: str, tol_pct: float) -> None:
    """Set ``status`` and the peak deviations from the reference method, in place."""
    ref = {c["case"]: c for c in cells if c["method"] == reference}
    for c in cells:
        r = ref.get(c["case"])
        c["amp_dev_pct"] = c["freq_dev_pct"] = None
        if c["succeeded"] and r is not None and r["succeeded"] and c is not r:
            lo, hi = c["band_hz"]
            c["amp_dev_pct"] = (
                100.0 * (c["peak_amplitude"] - r["peak_amplitude"]) / abs(r["peak_amplitude"])
            )
            c["freq_dev_pct"] = (
                100.0 * (c["peak_frequency_hz"] - r["peak_frequency_hz"]) / (hi - lo)
            )
        er = c.get("energy_residual_max")
        if not c["succeeded"]:
            c["status"] = "failed"
        elif (c["amp_dev_pct"] is not None and abs(c["amp_dev_pct"]) > tol_pct) or (
            er is not None and er > ENERGY_TOL
        ):
            c["status"] = "wrong"
        else:
            c["status"] = "ok"
        c["reference"] = c["method"] == reference
        c["reference_ok"] = bool(r is not None and r["succeeded"])

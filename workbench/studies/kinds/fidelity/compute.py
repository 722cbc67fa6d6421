"""The fidelity study: what each modelling knob costs and what it buys (issue 8).

One or more dampers under one or more loads (damper and phase x force, the
*conditions*; ``damper-phases`` picks the (damper, phase) pairs, by default
every damper at every phase) are solved at a *base* setting (the study's
own ``mesh-size``, ``contact-mesh-size``, ``modes``, ``harmonics``, ``nt``,
``points-per-line``, ``rigid-damper``), then with
ONE knob moved at a time to each of its ``levels-<knob>``, and once at the
*reference*: every varied knob at its finest level at once. For every
setting and condition the peak amplitude (mm), resonance frequency (Hz)
and friction energy per cycle at the peak (mJ) are compared with the
reference's: relative error ``|q - q_ref| / |q_ref|`` in percent. Beside it,
every setting's error against an extrapolated limit: per knob, Richardson
extrapolation of its ladder's finest three levels with the observed order
(``workbench.post.extrapolation``), the knobs' corrections added to the
reference (``workbench.post.fidelity.combined_limits``), flagged where a
knob's levels are not asymptotic. The tolerance pick judges a setting by
its errors against that limit where it is trusted and against the
reference elsewhere (``workbench.post.fidelity.pick_error``).

The time of a setting is what a user running that setting alone would pay:
geometry (gmsh), reduction (Craig-Bampton of rig and damper), assembly and
the harmonic balance of every condition (with several dampers, every
damper's model). Geometry and reduction times are
the compute times recorded in their cached records when they were built
(a stage shared by several settings is charged to each), so they do not
depend on whether this run found them cached; assembly and HBM times are
measured when the setting is solved and kept in its cache records.

A knob that does not reach a damper's model (points per line on the wedge)
keeps that damper at the base level: its cases are the base's, and the
knob neither corrects nor flags that damper's limit.

A setting is summed up by its *worst error*: the largest of the three
errors over every condition. The Pareto front is the set of settings that
no other setting beats in both time and worst error. With ``tolerance``
(percent) the study picks the cheapest measured setting whose worst error
is within it. A one-knob setting also carries the errors of the other
knobs at their base levels, so the study also proposes a combination: per
knob, the coarsest level whose error against that knob's OWN finest level
(other knobs at the base in both) is within the tolerance; it COMPUTES that
combination (one more case per condition) and measures its error against
the reference; if it misses, every knob moves one level finer and the new
combination is computed (at most ``_MAX_COMBOS``). A verified combination
is one more candidate of the pick. The reference itself is never a
candidate (its error is zero by construction).

Everything is cached: cases under ``out/cache/cases`` (the runner's keys),
stage times under ``out/cache/fidelity``; an interrupted study resumes and
a finished one is re-reported without solving anything.
"""

from __future__ import annotations

import itertools
import json
import logging
import time
from pathlib import Path
from typing import Any

from ....errors import InputError
from ....io import digest, write_json
from ....log import bars_enabled, progress_bar
from ....post.fidelity import (
    STAGES,
    Setting,
    combined_limits,
    condition_name,
    ladder_limits,
    ladder_self_errors,
    level_label,
    limit_errors,
    pick_basis,
    pick_error,
    relative_errors,
    setting_row,
    setting_value,
)
from ....post.knobs import KNOBS
from ....post.pareto import pareto_front, pick_cheapest
from ....post.results import CaseResult
from ...engine.outputs import write_manifest_and_report
from ...engine.plan import Case, make_case
from ...engine.runner import case_done
from ...engine.spec import StudySpec
from .ladders import (
    _check_sampling,
    _settings_dict,
    base_values,
    knob_applies,
    ladder_pivot,
    plan_settings,
    propose_combination,
    sampled,
)
from .options import damper_phases

log = logging.getLogger(__name__)

_MAX_COMBOS = 3


# ---- computing a setting ------------------------------------------------------------------


class _Computer:
    """Solves settings, reusing the case cache and the recorded stage times."""

    def __init__(self, spec: StudySpec, out: Path, force: bool):
        self.spec, self.out, self.force = spec, out, force
        self.base = spec.as_dict()
        pairs = damper_phases(spec)
        self.dampers = list(dict.fromkeys(d for d, _ in pairs))
        self.base_values = base_values(spec, self.dampers)
        # (damper, phase, force), the damper first, then the phase, then the force
        self.conditions = [
            (d, float(p), float(f)) for (d, p), f in itertools.product(pairs, spec.forces)
        ]
        several = len(self.dampers) > 1
        self.names = [condition_name(p, f, d if several else None) for d, p, f in self.conditions]
        self.case_dir = out / "cache" / "cases"
        self.time_dir = out / "cache" / "fidelity"
        self.case_dir.mkdir(parents=True, exist_ok=True)
        self.time_dir.mkdir(parents=True, exist_ok=True)
        self.n_computed = 0
        self.n_reused = 0
        self.n_models_prepared = 0
        self._fresh: set[str] = set()  # case digests computed in this run (force: redo once)
        self._prepared: dict[str, Any] = {}  # model digest -> PreparedModel (one at a time)
        self._model_stage_times: dict[str, dict[str, float]] = {}  # model digest -> stage -> s

    def cases(self, st: Setting) -> list[Case]:
        s = _settings_dict(self.base, st.values)
        out = []
        for d, p, f in self.conditions:
            sd = dict(s)
            for knob in KNOBS:  # a knob that does not reach this damper: its base level
                if not knob_applies(knob, d):
                    sd[knob] = self.base_values[knob]
            if st.role == "production":  # the production job's own model
                sd["geometry"] = self.spec.fidelity.production_geometry
            out.append(make_case(d, p, f, sd, st.label))
        return out

    def not_applicable(self, knobs) -> set[tuple[str, str]]:
        """The (knob, condition name) pairs where the knob does not reach the model."""
        return {
            (k, n)
            for k in knobs
            for (d, _, _), n in zip(self.conditions, self.names, strict=True)
            if not knob_applies(k, d)
        }

    def _done(self, c: Case) -> bool:
        if self.force and c.digest not in self._fresh:
            return False
        if not (self.time_dir / f"case-{c.digest}.json").is_file():
            return False
        return case_done(self.case_dir, c)

    def todo(self, settings: list[Setting]) -> list[Case]:
        seen: dict[str, Case] = {}
        for st in settings:
            for c in self.cases(st):
                if c.digest not in seen and not self._done(c):
                    seen[c.digest] = c
        return list(seen.values())

    def _model_times(self, case: Case, prep) -> dict[str, float]:
        """Compute times of the geometry and the reduction of ``case``'s model (recorded)."""
        from ....fe.reduce import reduce_body

        g = prep.geometry.stats.get("timings_s") or {}
        t_geom = float(sum(g.values())) if g else float(prep.timings.get("geometry", 0.0))
        s = case.settings
        fe_dir = self.out / "cache" / "fe"
        t_red = 0.0
        for body in ("rig", "damper"):
            rm = reduce_body(
                prep.geometry,
                body,
                n_modes=s["modes"],
                rigid=bool(s["rigid-damper"]) and body == "damper",
                cache_dir=fe_dir,
            )
            t_red += float(rm.timings.get("total", 0.0))
        return {
            "geometry": t_geom,
            "reduction": t_red,
            "assembly": float(prep.timings.get("assembly", 0.0)),
        }

    def solve(self, todo: list[Case], desc: str) -> None:
        """Compute the cases ``todo`` (grouped by model), saving case and time records."""
        from ....pipeline import prepare_model, solve_case

        if not todo:
            return
        order = sorted(todo, key=lambda c: c.model_digest)
        with progress_bar(f"{desc}: cases", total=len(order), unit="case") as bar:
            for k, c in enumerate(order):
                bar.set_postfix_str(f"{k + 1}/{len(order)} {c.name}")
                prep = self._prepared.get(c.model_digest)
                if prep is None:
                    self._prepared.clear()  # keep one model in memory at a time
                    log.info("model for %s: geometry, reduction, assembly", c.name)
                    prep = prepare_model(
                        c, self.out, force=self.force and c.model_digest not in self._fresh
                    )
                    self._fresh.add(c.model_digest)
                    self._model_stage_times[c.model_digest] = self._model_times(c, prep)
                    self._prepared[c.model_digest] = prep
                    self.n_models_prepared += 1
                res = solve_case(prep, c)
                res.save(self.case_dir / f"{c.digest}.h5")
                times = dict(
                    self._model_stage_times[c.model_digest], hbm=float(res.timings.get("hbm", 0.0))
                )
                write_json(self.time_dir / f"case-{c.digest}.json", times)
                self._fresh.add(c.digest)
                self.n_computed += 1
                if res.branch.failed:
                    log.warning(
                        "case %s stopped early: %s (its %d points are kept)",
                        c.name,
                        res.branch.message,
                        res.branch.n_points,
                    )
                bar.update(1)
                if not bars_enabled():
                    log.info(
                        "case %d/%d done: %s (%d points, %.1f s)",
                        k + 1,
                        len(order),
                        c.name,
                        res.branch.n_points,
                        res.timings.get("hbm", 0.0),
                    )

    def load(self, st: Setting) -> None:
        """Fill ``st.results`` and ``st.times`` from the cache (every case must be there)."""
        st.results, st.times = {}, {s: 0.0 for s in STAGES}
        models: set[str] = set()
        for name, c in zip(self.names, self.cases(st), strict=True):
            st.results[name] = CaseResult.load(self.case_dir / f"{c.digest}.h5")
            t = json.loads((self.time_dir / f"case-{c.digest}.json").read_text())
            if c.model_digest not in models:  # each model's stages: charged once per setting
                models.add(c.model_digest)
                for s in ("geometry", "reduction", "assembly"):
                    st.times[s] += float(t[s])
            st.times["hbm"] += float(t["hbm"])

    def run(self, settings: list[Setting], desc: str) -> None:
        todo = self.todo(settings)
        n_all = len({c.digest for st in settings for c in self.cases(st)})
        self.n_reused += n_all - len(todo)
        if todo:
            log.info(
                "%s: %d of %d cases to compute (%d cached)",
                desc,
                len(todo),
                n_all,
                n_all - len(todo),
            )
        self.solve(todo, desc)
        for st in settings:
            self.load(st)


# ---- the study ----------------------------------------------------------------------------


def _knob_limits(
    limits: dict[str, dict[str, dict[str, Any]]], ladders: dict[str, list[Setting]], base: Setting
) -> dict[str, dict[str, dict[str, dict[str, Any]]]]:
    """knob -> condition -> quantity -> the knob's limit estimate as a dict, with ``pivot``:
    the value at the ladder's level of the base's value of the knob (the base, or the base's
    value at the values the ladder holds: ``held_values``; None without such a level) and
    ``pivot_label``. The knob's error of the base is the pivot's against the knob's limit."""
    out: dict[str, dict[str, dict[str, dict[str, Any]]]] = {}
    for k, lim in limits.items():
        piv = ladder_pivot(k, ladders[k], base)
        out[k] = {
            c: {
                q: dict(
                    e.as_dict(),
                    pivot=setting_value(piv, c, q) if piv is not None else None,
                    pivot_label=piv.label if piv is not None else None,
                )
                for q, e in qs.items()
            }
            for c, qs in lim.items()
        }
    return out


def _held(ladders: dict[str, list[Setting]], base: Setting) -> dict[str, dict[str, str]]:
    """knob -> the label of each other knob its ladder holds away from the base
    (``held_values``), read off the ladder's pivot: where it differs from the base."""
    out: dict[str, dict[str, str]] = {}
    for k, lad in ladders.items():
        piv = ladder_pivot(k, lad, base)
        diff = {} if piv is None else {
            kk: level_label(kk, vv) for kk, vv in piv.values.items()
            if kk != k and vv != base.values[kk]
        }  # fmt: skip
        if diff:
            out[k] = diff
    return out


def run_fidelity(spec: StudySpec, out: str | Path, *, force: bool = False) -> dict[str, Any]:
    """Run a fidelity study into ``out`` (resuming); return the JSON summary."""
    from ....log import mpi_size

    out = Path(out)
    t_start = time.perf_counter()
    if mpi_size() > 1:  # the stage times must be those of one process; cases are not spread
        raise InputError(
            "mpirun -n",
            mpi_size(),
            "1: a fidelity study runs in one process (its times are what one process pays)",
        )
    if not spec.fidelity.knobs:
        raise InputError("knobs", spec.fidelity.knobs, "at least one knob to vary")
    comp = _Computer(spec, out, force)
    if spec.fidelity.production_geometry:  # its bad values refused now, not after the ladders
        from ....geometry import load_geometry_params

        for d in comp.dampers:
            load_geometry_params(d, spec.fidelity.production_geometry)
    if getattr(spec, "nonlinear_modes", False) and len(comp.dampers) > 1:
        raise InputError(
            "nonlinear-modes", True, "false in a fidelity study of several dampers (one damper)"
        )
    damper = ", ".join(comp.dampers)
    settings, ladders = plan_settings(spec, comp.dampers)
    ref = next(s for s in settings if s.role == "reference")
    log.info(
        "fidelity study '%s': %s, %d settings x %d conditions, reference %s",
        spec.name,
        damper,
        len(settings),
        len(comp.conditions),
        ", ".join(level_label(k, ref.values[k]) for k in ladders),
    )
    comp.run(settings, spec.name)
    for st in settings:
        st.errors = relative_errors(st, ref)
    if getattr(spec, "nonlinear_modes", False):  # the nonlinear-mode synthesis entry (nlmodes.py)
        from ...engine.nlmodes import fidelity_entry

        settings.append(fidelity_entry(comp, settings[0], ref, out))

    limits = ladder_limits(ladders, comp.not_applicable(ladders))
    combined = combined_limits(ref, ladders, limits)
    for st in settings:
        st.limit_errors = limit_errors(st, combined)
    production = None
    if spec.fidelity.production_geometry:  # the production job's model, at the base setting
        production = Setting("production", dict(settings[0].values), "production")
        comp.run([production], f"{spec.name}: production model")
        production.errors = relative_errors(production, ref)
        production.limit_errors = limit_errors(production, combined)
    pick = None
    combos: list[dict[str, Any]] = []
    if spec.fidelity.tolerance is not None:
        pick, combos, extra = _tolerance(
            spec.fidelity.tolerance, settings, ladders, comp, ref, combined
        )
        settings = settings + extra
    candidates = [s for s in settings if s.role != "reference"]
    front_idx = pareto_front([(s.time_s, s.error()) for s in candidates])
    front = [candidates[i] for i in front_idx]

    rows = [setting_row(s) for s in settings]
    front_labels = {s.label for s in front}
    for r in rows:
        r["on_front"] = r["label"] in front_labels
    if pick is not None:
        _log_pick(pick, spec.fidelity.tolerance)
    failures = [f"{s.label}: {m}" for s in settings for m in s.failed]
    for f in failures:
        log.warning("failed solve kept: %s", f)

    timings = {"total": time.perf_counter() - t_start}
    summary = {
        "study": spec.name,
        "kind": "fidelity",
        "out": str(out),
        "report": str(out / "report.html"),
        "damper": damper,
        "dampers": comp.dampers,
        "conditions": list(comp.names),
        "knobs": {k: [level_label(k, s.values[k]) for s in lad] for k, lad in ladders.items()},
        "knob_self_errors_pct": {
            k: {level_label(k, st.values[k]): e for st, e in zip(lad, errs, strict=True)}
            for (k, lad), errs in zip(
                ladders.items(), ladder_self_errors(ladders).values(), strict=True
            )
        },
        "knob_limits": _knob_limits(limits, ladders, settings[0]),
        "held": _held(ladders, settings[0]),
        "limit": combined,
        "base": {k: level_label(k, v) for k, v in settings[0].values.items()},
        "reference": {k: level_label(k, v) for k, v in ref.values.items()},
        "production_geometry": str(spec.fidelity.production_geometry or ""),
        "n_settings": len(settings),
        "n_computed": comp.n_computed,
        "n_reused": comp.n_reused,
        "n_models_prepared": comp.n_models_prepared,
        "settings": rows,
        "pareto_front": [s.label for s in front],
        "tolerance_pct": spec.fidelity.tolerance,
        "picked": pick,
        "combinations": combos,
        "failures": failures,
    }
    t_post = time.perf_counter()
    write_fidelity_outputs(
        spec, out, settings, ladders, ref, front, summary, comp.names, t_post - t_start, production
    )
    timings["post and report"] = time.perf_counter() - t_post
    timings["total"] = time.perf_counter() - t_start
    summary["timings_s"] = {k: round(v, 2) for k, v in timings.items()}
    write_json(out / "fidelity.json", summary)
    return summary


def _tolerance(
    tol: float,
    settings: list[Setting],
    ladders: dict[str, list[Setting]],
    comp: _Computer,
    ref: Setting,
    combined: dict[str, dict[str, dict[str, Any]]],
) -> tuple[dict, list[dict], list[Setting]]:
    """The tolerance pick: verified combinations first, then every measured setting.

    Each setting is judged by :func:`pick_error`: against the extrapolated limit where
    it is trusted, against the reference elsewhere (``combined``: the all-knob limit).
    """
    known = {s.key: s for s in settings}
    extra: list[Setting] = []
    combos: list[dict[str, Any]] = []
    self_err = ladder_self_errors(ladders)
    for shift in range(_MAX_COMBOS):
        prop = propose_combination(ladders, tol, shift, self_err)
        if prop is None:
            combos.append(
                {
                    "shift": shift,
                    "note": "some knob's levels could not be compared "
                    "with its finest level (failed solves): no combination proposed",
                }
            )
            break
        vals, why = prop
        full = sampled(settings[0].values, dict(settings[0].values, **vals))
        key = digest(full, 16)
        if key == ref.key:
            combos.append(
                {
                    "shift": shift,
                    "label": "reference",
                    "levels": why,
                    "note": "the combination is the reference itself (every knob needs "
                    "its finest level): not a candidate, its error is 0 by "
                    "construction",
                    "time_s": round(ref.time_s, 3),
                    "max_error_pct": None,
                    "meets": False,
                }
            )
            log.info("combination %d is the reference itself: nothing cheaper to verify", shift + 1)
            break
        if key in known:
            st = known[key]
            note = f"the combination is the already measured setting '{st.label}'"
        else:
            st = Setting(
                f"combined {shift + 1}", full, "combined", [("combined", ", ".join(why.values()))]
            )
            _check_sampling(full)
            n_before = comp.n_computed
            comp.run([st], f"combination {shift + 1}")
            st.errors = relative_errors(st, ref)
            st.limit_errors = limit_errors(st, combined)
            known[key] = st
            extra.append(st)
            note = (
                "computed to verify it"
                if comp.n_computed > n_before
                else "verified by computing it (its cases were found in the cache)"
            )
        err = pick_error(st, combined)
        ok = err is not None and err <= tol
        combos.append(
            {
                "shift": shift,
                "label": st.label,
                "levels": why,
                "note": note,
                "time_s": round(st.time_s, 3),
                "max_error_pct": err,
                "meets": ok,
            }
        )
        log.info(
            "combination %d (%s): %s; measured worst error %s -> %s",
            shift + 1,
            ", ".join(why.values()),
            note,
            "n/a" if err is None else f"{err:.3g} %",
            "meets the tolerance" if ok else "does NOT meet it",
        )
        if ok or all(st.values[k] == lad[-1].values[k] for k, lad in ladders.items()):
            break
    rows = []
    for s in list(settings) + extra:
        if s.role != "reference":
            rows.append(dict(setting_row(s), max_error_pct=pick_error(s, combined)))
    pick = pick_cheapest(rows, tol)
    pick["tolerance_pct"] = tol
    pick["basis"] = pick_basis(combined)
    pick["reason"] += f" ({pick['basis']})"
    if pick["picked"] is not None and pick["picked"]["role"] == "combined":
        pick["reason"] += " (a combination of per-knob levels, verified by computing it)"
    tried = [c for c in combos if c.get("label") not in (None, "reference")]
    if tried and not any(c["meets"] for c in tried):
        pick["reason"] += (
            f"; none of the {len(tried)} verified combination(s) met the "
            "tolerance, so the pick is a one-knob setting (or none)"
        )
    return pick, combos, extra


def _log_pick(pick: dict[str, Any], tol: float) -> None:
    if pick["met"]:
        p = pick["picked"]
        log.info(
            "tolerance %g %%: picked '%s' = %s; errors: amplitude %.3g %%, frequency "
            "%.3g %%, energy %.3g %%; time %.1f s. Why: %s",
            tol,
            p["label"],
            ", ".join(p[k] for k in KNOBS),
            p["err_peak_amplitude_mm_pct"],
            p["err_peak_frequency_hz_pct"],
            p["err_friction_energy_mj_pct"],
            p["time_s"],
            pick["reason"],
        )
    else:
        log.warning("tolerance %g %%: %s", tol, pick["reason"])


# ---- outputs ------------------------------------------------------------------------------


def write_fidelity_outputs(
    spec: StudySpec,
    out: Path,
    settings: list[Setting],
    ladders: dict[str, list[Setting]],
    ref: Setting,
    front: list[Setting],
    summary: dict[str, Any],
    conditions: list[str],
    wall_s: float = 0.0,
    production: Setting | None = None,
) -> None:
    """Tables (CSV, JSON), charts, manifest.json and report.html."""
    from .report import fidelity_outputs

    head, timings, sections = fidelity_outputs(
        out,
        settings,
        ladders,
        ref,
        front,
        summary,
        conditions,
        spec.fidelity.tolerance,
        wall_s,
        production,
    )
    write_manifest_and_report(out, spec, "fidelity study,", head, timings, sections)


__all__ = [
    "run_fidelity",
]

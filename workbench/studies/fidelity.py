"""The fidelity study: what each modelling knob costs and what it buys (issue 8).

One damper under one or more loads (phase x force, the *conditions*) is
solved at a *base* setting (the study's own ``mesh-size``, ``modes``,
``harmonics``, ``nt``, ``points-per-line``, ``rigid-damper``), then with
ONE knob moved at a time to each of its ``levels-<knob>``, and once at the
*reference*: every varied knob at its finest level at once. For every
setting and condition the peak amplitude (mm), resonance frequency (Hz)
and friction energy per cycle at the peak (mJ) are compared with the
reference's: relative error ``|q - q_ref| / |q_ref|`` in percent.

The time of a setting is what a user running that setting alone would pay:
geometry (gmsh), reduction (Craig-Bampton of rig and damper), assembly and
the harmonic balance of every condition. Geometry and reduction times are
the compute times recorded in their cached records when they were built
(a stage shared by several settings is charged to each), so they do not
depend on whether this run found them cached; assembly and HBM times are
measured when the setting is solved and kept in its cache records.

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
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..errors import InputError
from ..io import digest, write_json
from ..log import bars_enabled, progress_bar
from ..post.results import CaseResult
from ..post.tables import write_rows_csv
from .plan import Case, make_case
from .runner import case_done, write_manifest_and_report
from .spec import StudySpec

log = logging.getLogger(__name__)

KNOBS = ("mesh-size", "modes", "harmonics", "nt", "points-per-line", "rigid-damper")
QUANTITIES = (("peak_amplitude_mm", "peak amplitude", "mm"),
              ("peak_frequency_hz", "resonance frequency", "Hz"),
              ("friction_energy_mj", "friction energy per cycle", "mJ"))
STAGES = ("geometry", "reduction", "assembly", "hbm")
_MAX_COMBOS = 3


# ---- knob levels --------------------------------------------------------------------------


def parse_harmonics(text: Any, param: str = "levels-harmonics") -> list[int]:
    """'1' -> [1]; '0-3' -> [0, 1, 2, 3]; '1+3+5' -> [1, 3, 5]. Must contain 1."""
    allowed = "'a-b' (a range) or 'h+h+...' (a list) of harmonics >= 0 containing 1"
    s = str(text).strip()
    try:
        if "-" in s:
            a, b = (int(x) for x in s.split("-"))
            hs = list(range(a, b + 1))
        else:
            hs = [int(x) for x in s.split("+")]
    except ValueError:
        raise InputError(param, text, allowed) from None
    if not hs or 1 not in hs or min(hs) < 0 or len(set(hs)) != len(hs) or max(hs) > 64:
        raise InputError(param, text, allowed)
    return sorted(hs)


def harmonics_label(hs: list[int]) -> str:
    hs = sorted(hs)
    if len(hs) > 1 and hs == list(range(hs[0], hs[-1] + 1)):
        return f"{hs[0]}-{hs[-1]}"
    return "+".join(map(str, hs))


def level_label(knob: str, v: Any) -> str:
    """A short label of one knob value (used on the charts and in the tables)."""
    if knob == "mesh-size":
        return f"mesh {v:g} mm"
    if knob == "modes":
        return f"{v} modes"
    if knob == "harmonics":
        return f"H {harmonics_label(v)}"
    if knob == "nt":
        return f"nt {v}"
    if knob == "points-per-line":
        return f"{v} pts/line"
    if knob == "rigid-damper":
        return "rigid damper" if v else "flexible damper"
    raise AssertionError(knob)


def fineness(knob: str, v: Any) -> tuple:
    """Sort key: larger is finer (more accurate, more expensive)."""
    if knob == "mesh-size":
        return (-float(v),)
    if knob == "harmonics":
        return (max(v), len(v))
    if knob == "rigid-damper":
        return (0 if v else 1,)
    return (int(v),)


def base_values(spec: StudySpec, damper: str) -> dict[str, Any]:
    """The base setting's knob values, with 'file default' (None) resolved to numbers."""
    from ..geometry import load_geometry_params
    from ..hbm.fourier import default_nt

    v = {"mesh-size": spec.mesh_size, "modes": int(spec.modes),
         "harmonics": sorted(int(h) for h in spec.harmonics), "nt": spec.nt,
         "points-per-line": spec.points_per_line, "rigid-damper": bool(spec.rigid_damper)}
    if v["mesh-size"] is None or v["points-per-line"] is None:
        gp = load_geometry_params(damper, spec.geometry)
        if v["mesh-size"] is None:
            v["mesh-size"] = float(gp.rig.mesh.size_mm)
        if v["points-per-line"] is None:
            v["points-per-line"] = int(getattr(gp.shape, "n_contact_points", 0)) or None
    if v["nt"] is None:
        v["nt"] = default_nt(tuple(v["harmonics"]))
    return v


def knob_levels(spec: StudySpec) -> dict[str, list[Any]]:
    """knob -> its levels (settings values), coarsest first, for the knobs the study varies."""
    raw = {
        "mesh-size": [float(x) for x in spec.levels_mesh_size],
        "modes": [int(x) for x in spec.levels_modes],
        "harmonics": [parse_harmonics(x) for x in spec.levels_harmonics],
        "nt": [int(x) for x in spec.levels_nt],
        "points-per-line": [int(x) for x in spec.levels_points_per_line],
        "rigid-damper": [x == "rigid" for x in spec.levels_rigid_damper],
    }
    out: dict[str, list[Any]] = {}
    for knob in spec.knobs:
        levels = raw[knob]
        if not levels:
            raise InputError(f"levels-{knob}", levels, f"at least one level (or drop {knob} "
                             "from knobs)")
        keys = [json.dumps(x) for x in levels]
        if len(set(keys)) != len(keys):
            raise InputError(f"levels-{knob}", getattr(spec, f"levels_{knob}".replace("-", "_")),
                             "distinct levels")
        out[knob] = sorted(levels, key=lambda x, k=knob: fineness(k, x))
    return out


# ---- settings -----------------------------------------------------------------------------


@dataclass
class Setting:
    """One combination of knob values, its measured cases, times and errors."""

    label: str
    values: dict[str, Any]  # knob -> value (all six knobs)
    role: str = "knob"  # "base", "knob", "reference", "combined"
    members: list[tuple[str, str]] = field(default_factory=list)  # (knob, level label)
    results: dict[str, CaseResult] = field(default_factory=dict)  # condition -> case
    times: dict[str, float] = field(default_factory=dict)  # stage -> s (charged)
    errors: dict[str, dict[str, float | None]] = field(default_factory=dict)  # cond -> q -> %

    @property
    def key(self) -> str:
        return digest(self.values, 16)

    @property
    def time_s(self) -> float:
        return float(sum(self.times.get(s, 0.0) for s in STAGES))

    @property
    def failed(self) -> list[str]:
        return [f"{c}: {r.branch.message or 'no resonance peak'}"
                for c, r in self.results.items() if r.branch.failed or r.peak_index < 0]

    def error(self, q: str | None = None) -> float | None:
        """Largest error (percent) over the conditions, of quantity ``q`` or of all three."""
        return worst(self.errors, q)


def worst(errors: dict[str, dict[str, float | None]], q: str | None = None) -> float | None:
    """Largest of ``errors[condition][quantity]`` (percent); None if any is missing."""
    qs = [q] if q else [k for k, _, _ in QUANTITIES]
    vals = [errors.get(c, {}).get(k) for c in errors for k in qs]
    if not errors or any(v is None or not math.isfinite(v) for v in vals):
        return None
    return max(vals)


def condition_name(phase: float, force: float) -> str:
    return f"{phase:g} deg {force:g} N"


def _settings_dict(base: dict[str, Any], values: dict[str, Any]) -> dict[str, Any]:
    s = dict(base)
    for k, v in values.items():
        s[k] = list(v) if isinstance(v, list) else v
    return s


def plan_settings(spec: StudySpec, damper: str) -> tuple[list[Setting], dict[str, list[Setting]]]:
    """The unique settings (base, one-knob ladders, reference) and each knob's ladder."""
    base_v = base_values(spec, damper)
    levels = knob_levels(spec)
    unique: dict[str, Setting] = {}

    def add(values: dict[str, Any], label: str, role: str) -> Setting:
        st = Setting(label, values, role)
        if st.key in unique:
            return unique[st.key]
        unique[st.key] = st
        return st

    base = add(dict(base_v), "base", "base")
    base.members.append(("base", "base"))
    ladders: dict[str, list[Setting]] = {}
    for knob, lv in levels.items():
        ladders[knob] = []
        for v in lv:
            vals = dict(base_v, **{knob: v})
            st = add(vals, level_label(knob, v), "knob")
            st.members.append((knob, level_label(knob, v)))
            ladders[knob].append(st)
    ref_v = dict(base_v)
    for knob, lv in levels.items():
        ref_v[knob] = max(lv + [base_v[knob]], key=lambda x, k=knob: fineness(k, x))
    ref = add(ref_v, "reference", "reference")
    ref.role, ref.label = "reference", "reference"  # may coincide with a knob's finest level
    ref.members.append(("reference", "reference"))
    for st in unique.values():
        _check_sampling(st.values)
    return list(unique.values()), ladders


def _check_sampling(v: dict[str, Any]) -> None:
    if v["nt"] <= 2 * max(v["harmonics"]):
        raise InputError("levels-nt", v["nt"], f"nt > 2 * max(harmonics) = "
                         f"{2 * max(v['harmonics'])} for every setting (sampling theorem)")


# ---- computing a setting ------------------------------------------------------------------


class _Computer:
    """Solves settings, reusing the case cache and the recorded stage times."""

    def __init__(self, spec: StudySpec, damper: str, out: Path, force: bool):
        self.spec, self.damper, self.out, self.force = spec, damper, out, force
        self.base = spec.as_dict()
        self.conditions = [(float(p), float(f)) for p, f in
                           itertools.product(spec.phases, spec.forces)]
        self.case_dir = out / "cache" / "cases"
        self.time_dir = out / "cache" / "fidelity"
        self.case_dir.mkdir(parents=True, exist_ok=True)
        self.time_dir.mkdir(parents=True, exist_ok=True)
        self.n_computed = 0
        self.n_reused = 0
        self.n_models_prepared = 0
        self._fresh: set[str] = set()  # case digests computed in this run (force: redo once)
        self._prepared: dict[str, Any] = {}

    def cases(self, st: Setting) -> list[Case]:
        s = _settings_dict(self.base, st.values)
        return [make_case(self.damper, p, f, s, st.label) for p, f in self.conditions]

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
        from ..fe.reduce import reduce_body

        g = prep.geometry.stats.get("timings_s") or {}
        t_geom = float(sum(g.values())) if g else float(prep.timings.get("geometry", 0.0))
        s = case.settings
        fe_dir = self.out / "cache" / "fe"
        t_red = 0.0
        for body in ("rig", "damper"):
            rm = reduce_body(prep.geometry, body, n_modes=s["modes"],
                             rigid=bool(s["rigid-damper"]) and body == "damper",
                             cache_dir=fe_dir)
            t_red += float(rm.timings.get("total", 0.0))
        return {"geometry": t_geom, "reduction": t_red,
                "assembly": float(prep.timings.get("assembly", 0.0))}

    def solve(self, todo: list[Case], desc: str) -> None:
        """Compute the cases ``todo`` (grouped by model), saving case and time records."""
        from .runner import prepare_model, solve_case

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
                    prep = prepare_model(c, self.out, force=self.force
                                         and c.model_digest not in self._fresh)
                    self._fresh.add(c.model_digest)
                    prep.model_times = self._model_times(c, prep)  # type: ignore[attr-defined]
                    self._prepared[c.model_digest] = prep
                    self.n_models_prepared += 1
                res = solve_case(prep, c)
                res.save(self.case_dir / f"{c.digest}.h5")
                times = dict(prep.model_times, hbm=float(res.timings.get("hbm", 0.0)))  # type: ignore[attr-defined]
                write_json(self.time_dir / f"case-{c.digest}.json", times)
                self._fresh.add(c.digest)
                self.n_computed += 1
                if res.branch.failed:
                    log.warning("case %s stopped early: %s (its %d points are kept)", c.name,
                                res.branch.message, res.branch.n_points)
                bar.update(1)
                if not bars_enabled():
                    log.info("case %d/%d done: %s (%d points, %.1f s)", k + 1, len(order),
                             c.name, res.branch.n_points, res.timings.get("hbm", 0.0))

    def load(self, st: Setting) -> None:
        """Fill ``st.results`` and ``st.times`` from the cache (every case must be there)."""
        st.results, st.times = {}, {s: 0.0 for s in STAGES}
        for (p, f), c in zip(self.conditions, self.cases(st), strict=True):
            st.results[condition_name(p, f)] = CaseResult.load(
                self.case_dir / f"{c.digest}.h5")
            t = json.loads((self.time_dir / f"case-{c.digest}.json").read_text())
            for s in ("geometry", "reduction", "assembly"):
                st.times[s] = float(t[s])  # the model's stages: charged once per setting
            st.times["hbm"] += float(t["hbm"])

    def run(self, settings: list[Setting], desc: str) -> None:
        todo = self.todo(settings)
        n_all = len({c.digest for st in settings for c in self.cases(st)})
        self.n_reused += n_all - len(todo)
        if todo:
            log.info("%s: %d of %d cases to compute (%d cached)", desc, len(todo), n_all,
                     n_all - len(todo))
        self.solve(todo, desc)
        for st in settings:
            self.load(st)


# ---- errors, Pareto front, tolerance pick -------------------------------------------------


def relative_errors(st: Setting, ref: Setting) -> dict[str, dict[str, float | None]]:
    """condition -> quantity -> |q - q_ref| / |q_ref| in percent (None: no value to compare)."""
    out: dict[str, dict[str, float | None]] = {}
    for cond, r in st.results.items():
        rr = ref.results.get(cond)
        s = r.summary() if not r.branch.failed else {}
        sr = rr.summary() if rr is not None and not rr.branch.failed else {}
        out[cond] = {}
        for q, _, _ in QUANTITIES:
            a, b = s.get(q), sr.get(q)
            out[cond][q] = (abs(a - b) / abs(b) * 100.0 if a is not None and b is not None
                            and b != 0 else None)
    return out


def pareto_front(points: list[tuple[float, float | None]]) -> list[int]:
    """Indices of the non-dominated (time, error) points, cheapest first.

    A point is dominated when another is no slower and no less accurate and
    strictly better in one of the two. Points without an error (None, NaN)
    are never on the front.
    """
    ok = [i for i, (t, e) in enumerate(points) if e is not None and math.isfinite(e)]
    ok.sort(key=lambda i: (points[i][0], points[i][1]))
    front: list[int] = []
    best = math.inf
    for i in ok:
        if points[i][1] < best:
            front.append(i)
            best = points[i][1]
    return front


def pick_cheapest(rows: list[dict[str, Any]], tolerance_pct: float) -> dict[str, Any]:
    """The cheapest row whose ``max_error_pct`` is within the tolerance.

    ``rows``: dicts with ``label``, ``time_s`` and ``max_error_pct`` (None
    for a setting that could not be compared). Returns ``{"met": bool,
    "picked": row or None, "closest": row or None, "reason": str}``; when
    nothing meets the tolerance, ``closest`` is the most accurate row.
    """
    valid = [r for r in rows if r.get("max_error_pct") is not None
             and math.isfinite(r["max_error_pct"])]
    meeting = [r for r in valid if r["max_error_pct"] <= tolerance_pct]
    if meeting:
        best = min(meeting, key=lambda r: (r["time_s"], r["max_error_pct"]))
        return {"met": True, "picked": best, "closest": best, "reason": (
            f"'{best['label']}' is the cheapest of the {len(meeting)} of {len(rows)} measured "
            f"settings whose worst error ({best['max_error_pct']:.3g} %) is within "
            f"{tolerance_pct:g} %: {best['time_s']:.1f} s")}
    if not valid:
        return {"met": False, "picked": None, "closest": None, "reason": (
            f"no setting meets {tolerance_pct:g} %: none of the {len(rows)} settings could be "
            "compared with the reference (failed solves)")}
    close = min(valid, key=lambda r: (r["max_error_pct"], r["time_s"]))
    return {"met": False, "picked": None, "closest": close, "reason": (
        f"NO setting meets {tolerance_pct:g} %: the closest is '{close['label']}' with a worst "
        f"error of {close['max_error_pct']:.3g} % ({close['time_s']:.1f} s); refine the "
        "levels or loosen the tolerance")}


def ladder_self_errors(ladders: dict[str, list[Setting]]) -> dict[str, list[float | None]]:
    """knob -> worst error (percent) of each level against the knob's OWN finest level.

    The other knobs stay at the base in both, so this is the error that knob
    alone makes (its convergence), free of the other knobs' errors that every
    one-knob setting carries against the reference.
    """
    return {knob: [worst(relative_errors(st, lad[-1])) for st in lad]
            for knob, lad in ladders.items()}


def propose_combination(ladders: dict[str, list[Setting]], tolerance_pct: float,
                        shift: int = 0, errors: dict[str, list[float | None]] | None = None,
                        ) -> tuple[dict[str, Any], dict[str, str]] | None:
    """Per knob, the coarsest level whose error meets the tolerance (``shift`` levels finer).

    ``errors``: knob -> the error of each level (percent, coarsest first);
    default: each one-knob setting's error against the reference. Returns
    (knob -> value, knob -> why) or None when a knob has no level meeting
    the tolerance.
    """
    values: dict[str, Any] = {}
    why: dict[str, str] = {}
    for knob, ladder in ladders.items():
        errs = errors[knob] if errors is not None else [st.error() for st in ladder]
        idx = [i for i, e in enumerate(errs) if e is not None and e <= tolerance_pct]
        if not idx:
            return None
        i = min(idx[0] + shift, len(ladder) - 1)
        values[knob] = ladder[i].values[knob]
        e = errs[i]
        why[knob] = (f"{level_label(knob, values[knob])} ({e:.3g} %)" if e is not None
                     else level_label(knob, values[knob]))
    return values, why


def setting_row(st: Setting) -> dict[str, Any]:
    row: dict[str, Any] = {"label": st.label, "role": st.role,
                           "knobs": "; ".join(f"{k}={m}" for k, m in st.members)}
    for k in KNOBS:
        row[k] = level_label(k, st.values[k])
    for s in STAGES:
        row[f"{s}_s"] = round(st.times.get(s, 0.0), 3)
    row["time_s"] = round(st.time_s, 3)
    for q, _, _ in QUANTITIES:
        e = st.error(q)
        row[f"err_{q}_pct"] = e
    row["max_error_pct"] = st.error()
    row["failed"] = "; ".join(st.failed)
    return row


# ---- the study ----------------------------------------------------------------------------


def run_fidelity(spec: StudySpec, out: str | Path, *, force: bool = False) -> dict[str, Any]:
    """Run a fidelity study into ``out`` (resuming); return the JSON summary."""
    from ..log import mpi_size

    out = Path(out)
    t_start = time.perf_counter()
    if mpi_size() > 1:  # the stage times must be those of one process; cases are not spread
        raise InputError("mpirun -n", mpi_size(), "1: a fidelity study runs in one process "
                         "(its times are what one process pays)")
    if len(spec.dampers) != 1:
        raise InputError("dampers", spec.dampers, "exactly one damper in a fidelity study")
    damper = spec.dampers[0]
    if not spec.knobs:
        raise InputError("knobs", spec.knobs, "at least one knob to vary")
    settings, ladders = plan_settings(spec, damper)
    comp = _Computer(spec, damper, out, force)
    ref = next(s for s in settings if s.role == "reference")
    log.info("fidelity study '%s': %s, %d settings x %d conditions, reference %s", spec.name,
             damper, len(settings), len(comp.conditions),
             ", ".join(level_label(k, ref.values[k]) for k in ladders))
    comp.run(settings, spec.name)
    for st in settings:
        st.errors = relative_errors(st, ref)
    if getattr(spec, "nonlinear_modes", False):  # the nonlinear-mode synthesis entry (nlmodes.py)
        from .nlmodes import fidelity_entry

        settings.append(fidelity_entry(comp, settings[0], ref, out))

    pick = None
    combos: list[dict[str, Any]] = []
    if spec.tolerance is not None:
        pick, combos, extra = _tolerance(spec.tolerance, settings, ladders, comp, ref)
        settings = settings + extra
    candidates = [s for s in settings if s.role != "reference"]
    front_idx = pareto_front([(s.time_s, s.error()) for s in candidates])
    front = [candidates[i] for i in front_idx]

    rows = [setting_row(s) for s in settings]
    front_labels = {s.label for s in front}
    for r in rows:
        r["on_front"] = r["label"] in front_labels
    if pick is not None:
        _log_pick(pick, spec.tolerance)
    failures = [f"{s.label}: {m}" for s in settings for m in s.failed]
    for f in failures:
        log.warning("failed solve kept: %s", f)

    timings = {"total": time.perf_counter() - t_start}
    summary = {
        "study": spec.name, "kind": "fidelity", "out": str(out),
        "report": str(out / "report.html"), "damper": damper,
        "conditions": [condition_name(p, f) for p, f in comp.conditions],
        "knobs": {k: [level_label(k, s.values[k]) for s in lad] for k, lad in ladders.items()},
        "knob_self_errors_pct": {
            k: {level_label(k, st.values[k]): e for st, e in zip(lad, errs, strict=True)}
            for (k, lad), errs in zip(ladders.items(), ladder_self_errors(ladders).values(),
                                      strict=True)},
        "base": {k: level_label(k, v) for k, v in settings[0].values.items()},
        "reference": {k: level_label(k, v) for k, v in ref.values.items()},
        "n_settings": len(settings), "n_computed": comp.n_computed, "n_reused": comp.n_reused,
        "n_models_prepared": comp.n_models_prepared,
        "settings": rows,
        "pareto_front": [s.label for s in front],
        "tolerance_pct": spec.tolerance,
        "picked": pick, "combinations": combos,
        "failures": failures,
    }
    t_post = time.perf_counter()
    write_fidelity_outputs(spec, out, settings, ladders, ref, front, summary, comp.conditions,
                           t_post - t_start)
    timings["post and report"] = time.perf_counter() - t_post
    timings["total"] = time.perf_counter() - t_start
    summary["timings_s"] = {k: round(v, 2) for k, v in timings.items()}
    write_json(out / "fidelity.json", summary)
    return summary


def _tolerance(tol: float, settings: list[Setting], ladders: dict[str, list[Setting]],
               comp: _Computer, ref: Setting) -> tuple[dict, list[dict], list[Setting]]:
    """The tolerance pick: verified combinations first, then every measured setting."""
    known = {s.key: s for s in settings}
    extra: list[Setting] = []
    combos: list[dict[str, Any]] = []
    self_err = ladder_self_errors(ladders)
    for shift in range(_MAX_COMBOS):
        prop = propose_combination(ladders, tol, shift, self_err)
        if prop is None:
            combos.append({"shift": shift, "note": "some knob's levels could not be compared "
                           "with its finest level (failed solves): no combination proposed"})
            break
        vals, why = prop
        full = dict(settings[0].values, **vals)
        key = digest(full, 16)
        if key == ref.key:
            combos.append({"shift": shift, "label": "reference", "levels": why,
                           "note": "the combination is the reference itself (every knob needs "
                           "its finest level): not a candidate, its error is 0 by "
                           "construction", "time_s": round(ref.time_s, 3),
                           "max_error_pct": None, "meets": False})
            log.info("combination %d is the reference itself: nothing cheaper to verify",
                     shift + 1)
            break
        if key in known:
            st = known[key]
            note = f"the combination is the already measured setting '{st.label}'"
        else:
            st = Setting(f"combined {shift + 1}", full, "combined",
                         [("combined", ", ".join(why.values()))])
            _check_sampling(full)
            n_before = comp.n_computed
            comp.run([st], f"combination {shift + 1}")
            st.errors = relative_errors(st, ref)
            known[key] = st
            extra.append(st)
            note = ("computed to verify it" if comp.n_computed > n_before else
                    "verified by computing it (its cases were found in the cache)")
        err = st.error()
        ok = err is not None and err <= tol
        combos.append({"shift": shift, "label": st.label, "levels": why, "note": note,
                       "time_s": round(st.time_s, 3), "max_error_pct": err, "meets": ok})
        log.info("combination %d (%s): %s; measured worst error %s -> %s", shift + 1,
                 ", ".join(why.values()), note, "n/a" if err is None else f"{err:.3g} %",
                 "meets the tolerance" if ok else "does NOT meet it")
        if ok or all(st.values[k] == lad[-1].values[k] for k, lad in ladders.items()):
            break
    rows = [setting_row(s) for s in list(settings) + extra if s.role != "reference"]
    pick = pick_cheapest(rows, tol)
    pick["tolerance_pct"] = tol
    if pick["picked"] is not None and pick["picked"]["role"] == "combined":
        pick["reason"] += " (a combination of per-knob levels, verified by computing it)"
    tried = [c for c in combos if c.get("label") not in (None, "reference")]
    if tried and not any(c["meets"] for c in tried):
        pick["reason"] += (f"; none of the {len(tried)} verified combination(s) met the "
                           "tolerance, so the pick is a one-knob setting (or none)")
    return pick, combos, extra


def _log_pick(pick: dict[str, Any], tol: float) -> None:
    if pick["met"]:
        p = pick["picked"]
        log.info("tolerance %g %%: picked '%s' = %s; errors: amplitude %.3g %%, frequency "
                 "%.3g %%, energy %.3g %%; time %.1f s. Why: %s", tol, p["label"],
                 ", ".join(p[k] for k in KNOBS), p["err_peak_amplitude_mm_pct"],
                 p["err_peak_frequency_hz_pct"], p["err_friction_energy_mj_pct"], p["time_s"],
                 pick["reason"])
    else:
        log.warning("tolerance %g %%: %s", tol, pick["reason"])


# ---- outputs ------------------------------------------------------------------------------


def write_csv(path: Path, rows: list[dict[str, Any]], cols: list[str] | None = None) -> Path:
    """The fidelity tables: four significant digits are plenty for errors and times."""
    return write_rows_csv(path, rows, cols, digits=4)


def condition_rows(settings: list[Setting]) -> list[dict[str, Any]]:
    """One row per setting and condition: values and errors."""
    rows = []
    for st in settings:
        for cond, r in st.results.items():
            s = r.summary()
            row = {"label": st.label, "role": st.role, "condition": cond,
                   "failed": r.branch.failed}
            for q, _, _ in QUANTITIES:
                row[q] = s.get(q)
                row[f"err_{q}_pct"] = st.errors.get(cond, {}).get(q)
            row["hbm_s"] = round(float(r.timings.get("hbm", 0.0)), 3)
            rows.append(row)
    return rows


def write_fidelity_outputs(spec: StudySpec, out: Path, settings: list[Setting],
                           ladders: dict[str, list[Setting]], ref: Setting, front: list[Setting],
                           summary: dict[str, Any], conditions: list[tuple[float, float]],
                           wall_s: float = 0.0) -> None:
    """Tables (CSV, JSON), charts, manifest.json and report.html."""
    from ..render.fidelity_figures import plot_knob, plot_pareto

    tables, figs = out / "tables", out / "figures"
    rows = summary["settings"]
    cols = ["label", "role", *KNOBS, "geometry_s", "reduction_s", "assembly_s", "hbm_s",
            "time_s", "err_peak_amplitude_mm_pct", "err_peak_frequency_hz_pct",
            "err_friction_energy_mj_pct", "max_error_pct", "on_front", "failed"]
    write_csv(tables / "fidelity_settings.csv", rows, cols)
    write_csv(tables / "fidelity_cases.csv", condition_rows(settings))
    write_json(tables / "fidelity_settings.json", rows)
    by_label = {r["label"]: r for r in rows}
    front_rows = [by_label[s.label] for s in front]
    write_csv(tables / "fidelity_pareto.csv", front_rows,
              ["label", "time_s", "max_error_pct", "err_peak_amplitude_mm_pct",
               "err_peak_frequency_hz_pct", "err_friction_energy_mj_pct"])

    conds = [condition_name(p, f) for p, f in conditions]
    sections = [_setup_section(spec, summary, ref, conds)]
    self_err = ladder_self_errors(ladders)
    for knob, lad in ladders.items():
        fig = plot_knob(knob, [level_label(knob, s.values[knob]) for s in lad],
                        [s.time_s for s in lad],
                        {q: {c: [s.errors.get(c, {}).get(q) for s in lad] for c in conds}
                         for q, _, _ in QUANTITIES}, figs / f"fidelity_{knob}.png")
        trows = []
        for s, own in zip(lad, self_err[knob], strict=True):
            r = by_label[s.label]
            for c in conds:
                trows.append({"level": level_label(knob, s.values[knob]), "condition": c,
                              **{f"{q} error %": s.errors.get(c, {}).get(q)
                                 for q, _, _ in QUANTITIES},
                              "worst error vs the knob's finest level %": own,
                              "time s": r["time_s"], "failed": "; ".join(s.failed)})
        write_csv(tables / f"fidelity_{knob}.csv", trows)
        sections.append({
            "id": f"knob-{knob}", "title": f"Knob: {knob}",
            "text": [f"{knob} moved over {len(lad)} levels, the other knobs at the base "
                     "setting. Errors relative to the reference, in percent; time is the "
                     "whole cost of the setting (geometry + reduction + assembly + HBM of "
                     f"every condition), s. Log-log; errors below {1e-4:g} % are drawn at "
                     f"{1e-4:g} % (open markers). Against the reference, a one-knob setting "
                     "also carries the errors of the other knobs at their base levels; the "
                     "table's last error column compares each level with this knob's own "
                     "finest level instead (the error this knob alone makes)."],
            "figures": [{"path": str(fig.relative_to(out)),
                         "caption": f"error vs compute time when only {knob} changes"}],
            "tables": [{"path": f"tables/fidelity_{knob}.csv",
                        "caption": f"{knob}: errors per condition and time"}]})
    tol = spec.tolerance
    picked = (summary.get("picked") or {}).get("picked")
    cand = [s for s in settings if s.role != "reference"]
    fig = plot_pareto(
        [{"label": s.label, "group": (s.members[0][0] if s.members else s.role),
          "time_s": s.time_s, **{q: s.error(q) for q, _, _ in QUANTITIES},
          "worst": s.error()} for s in cand],
        figs / "fidelity_pareto.png", tolerance_pct=tol,
        picked=picked["label"] if picked else None, reference_time_s=ref.time_s)
    sections.append({
        "id": "pareto", "title": "All settings and the Pareto front",
        "text": [f"Every measured setting (one knob moved, the base, and any verified "
                 f"combination) against its compute time; each panel's line is the Pareto "
                 f"front of that error (no setting is both cheaper and more accurate). The "
                 f"last panel is the worst of the three errors over every condition, the "
                 f"measure the tolerance uses. Front: {', '.join(summary['pareto_front'])}."],
        "figures": [{"path": str(fig.relative_to(out)), "caption": "error vs time, all knobs"}],
        "tables": [{"path": "tables/fidelity_pareto.csv", "caption": "the Pareto front "
                    "(worst error)"},
                   {"path": "tables/fidelity_settings.csv", "caption": "every setting: "
                    "knob levels, charged time per stage (s), worst errors (%)"}]})
    sections.append(_pick_section(summary, tol))
    if summary["failures"]:
        sections.append({"id": "failures", "title": "Failed solves",
                         "text": ["These cases stopped early; their points are kept, and the "
                                  "settings they belong to have no error and are never "
                                  "picked:"] + summary["failures"], "figures": [],
                         "tables": []})
    sections.append({"id": "cases", "title": "Every case", "text": [
        "One row per setting and condition: the peak values and their errors."],
        "figures": [], "tables": [{"path": "tables/fidelity_cases.csv",
                                   "caption": "every case"}]})
    head = [f"{damper_line(summary)}",
            f"reference: {_kv(summary['reference'])}",
            f"Pareto front (worst error): {', '.join(summary['pareto_front'])}"]
    if summary.get("picked"):
        head.append(summary["picked"]["reason"])
    timings = {"wall time of this run (before the report)": wall_s,
               **{f"{s} (charged, summed over the settings)":
                  sum(x.times.get(s, 0.0) for x in settings) for s in STAGES}}
    write_manifest_and_report(out, spec, "fidelity study,", head, timings, sections)


def damper_line(summary: dict[str, Any]) -> str:
    return (f"{summary['damper']}: {summary['n_settings']} settings x "
            f"{len(summary['conditions'])} conditions ({', '.join(summary['conditions'])}); "
            f"{summary['n_computed']} cases computed, {summary['n_reused']} reused")


def _kv(d: dict[str, Any]) -> str:
    return ", ".join(str(v) for v in d.values())  # the level labels name their knob


def _setup_section(spec: StudySpec, summary: dict[str, Any], ref: Setting,
                   conds: list[str]) -> dict[str, Any]:
    knobs = "; ".join(f"{k}: {', '.join(v)}" for k, v in summary["knobs"].items())
    return {"id": "setup", "title": "Setup and reference", "text": [
        damper_line(summary) + ".",
        f"Base setting: {_kv(summary['base'])}. Levels tried, one knob at a time: {knobs}.",
        f"Reference (every varied knob at its finest level at once): "
        f"{_kv(summary['reference'])}; its charged time {ref.time_s:.1f} s.",
        "Errors: |q - q_ref| / |q_ref| in percent for the peak amplitude (mm), the resonance "
        "frequency (Hz) and the friction energy per cycle at the peak (mJ), at every "
        "condition. Times: geometry and reduction are the compute times recorded when those "
        "stages were built (a stage shared by several settings is charged to each, as a user "
        "running that setting alone would pay it), assembly and HBM as measured when the "
        "setting was solved; the machine may have been shared, so times are indicative.",
    ], "figures": [], "tables": []}


def _pick_section(summary: dict[str, Any], tol: float | None) -> dict[str, Any]:
    if tol is None:
        return {"id": "pick", "title": "Tolerance pick", "text": [
            "No tolerance given (run with --tolerance 1% to pick the cheapest setting)."],
            "figures": [], "tables": []}
    pick = summary["picked"]
    text = [pick["reason"]]
    p = pick.get("picked")
    if p:
        text.append("Picked: " + ", ".join(p[k] for k in KNOBS) + "; errors: "
                    f"amplitude {p['err_peak_amplitude_mm_pct']:.3g} %, frequency "
                    f"{p['err_peak_frequency_hz_pct']:.3g} %, energy "
                    f"{p['err_friction_energy_mj_pct']:.3g} %; time {p['time_s']:.1f} s.")
    for c in summary["combinations"]:
        if "label" in c:
            e = c["max_error_pct"]
            text.append(f"Combination {c['shift'] + 1} (per knob, the coarsest level within "
                        f"{tol:g} % of that knob's own finest level, {c['shift']} level(s) "
                        "finer; in brackets that error): "
                        f"{', '.join(c['levels'].values())}; {c['note']}; measured worst "
                        f"error {'n/a' if e is None else f'{e:.3g} %'}, "
                        f"{'meets' if c['meets'] else 'does not meet'} the tolerance; "
                        f"{c['time_s']:.1f} s.")
        else:
            text.append(f"Combination: {c['note']}.")
    return {"id": "pick", "title": f"Tolerance pick ({tol:g} %)", "text": text,
            "figures": [], "tables": []}


__all__ = ["run_fidelity", "pareto_front", "pick_cheapest", "parse_harmonics",
           "propose_combination", "relative_errors"]

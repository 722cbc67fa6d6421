"""The fidelity study's records and measures: settings, their labels and their errors.

A :class:`Setting` is one combination of the six modelling knobs with its
measured cases, charged stage times and relative errors against the
reference. This module holds the knob vocabulary (names, labels, which
level is finer), the error measures (``relative_errors``, ``worst``,
``ladder_self_errors``) and one table row per setting (``setting_row``).
It is plain data on computed :class:`~workbench.post.results.CaseResult`
records: the study (``workbench.studies.kinds.fidelity.compute``) fills it, the report
(``workbench.studies.kinds.fidelity.report``) draws it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

from ..io import digest
from .extrapolation import SAFETY, LimitEstimate, fit_scatter, richardson
from .knobs import KNOBS
from .results import CaseResult

QUANTITIES = (
    ("peak_amplitude_mm", "peak amplitude", "mm"),
    ("peak_frequency_hz", "resonance frequency", "Hz"),
    ("friction_energy_mj", "friction energy per cycle", "mJ"),
)


# values at or below these are zero (quantity -> floor, its units): a damper stuck at the
# peak dissipates nothing, and its loop integral comes out as round-off (1e-18..1e-16 mJ on
# the rigs here), whose relative differences would read as errors of 100-1000 %
ROUND_OFF_ZERO = {"friction_energy_mj": 1e-12}

STAGES = ("geometry", "reduction", "assembly", "hbm")


def zeroed(q: str, v: float | None) -> float | None:
    """``v`` with a round-off value of a quantity that is physically zero set to 0."""
    if v is None or abs(v) > ROUND_OFF_ZERO.get(q, 0.0):
        return v
    return 0.0


def harmonics_label(hs: list[int]) -> str:
    hs = sorted(hs)
    if len(hs) > 1 and hs == list(range(hs[0], hs[-1] + 1)):
        return f"{hs[0]}-{hs[-1]}"
    return "+".join(map(str, hs))


def level_label(knob: str, v: Any) -> str:
    """A short label of one knob value (used on the charts and in the tables)."""
    if knob == "mesh-size":
        return f"mesh {v:g} mm"
    if knob == "contact-mesh-size":
        return f"contact {v:g} mm"
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
    if knob in ("mesh-size", "contact-mesh-size"):
        return (-float(v),)
    if knob == "harmonics":
        return (max(v), len(v))
    if knob == "rigid-damper":
        return (0 if v else 1,)
    return (int(v),)


@dataclass
class Setting:
    """One combination of knob values, its measured cases, times and errors."""

    label: str
    values: dict[str, Any]  # knob -> value (every knob of KNOBS)
    role: str = "knob"  # "base", "knob", "reference", "combined"
    members: list[tuple[str, str]] = field(default_factory=list)  # (knob, level label)
    results: dict[str, CaseResult] = field(default_factory=dict)  # condition -> case
    times: dict[str, float] = field(default_factory=dict)  # stage -> s (charged)
    errors: dict[str, dict[str, float | None]] = field(default_factory=dict)  # cond -> q -> %
    # against the extrapolated limit (see ``combined_limits``): cond -> q -> %
    limit_errors: dict[str, dict[str, float | None]] = field(default_factory=dict)

    @property
    def key(self) -> str:
        return digest(self.values, 16)

    @property
    def time_s(self) -> float:
        return float(sum(self.times.get(s, 0.0) for s in STAGES))

    @property
    def failed(self) -> list[str]:
        return [
            f"{c}: {r.branch.message or 'no resonance peak'}"
            for c, r in self.results.items()
            if r.branch.failed or r.peak_index < 0
        ]

    def error(self, q: str | None = None) -> float | None:
        """Largest error (percent) over the conditions, of quantity ``q`` or of all three."""
        return worst(self.errors, q)

    def limit_error(self, q: str | None = None) -> float | None:
        """Largest error (percent) against the extrapolated limit, of ``q`` or of all three."""
        return worst(self.limit_errors, q)


def worst(errors: dict[str, dict[str, float | None]], q: str | None = None) -> float | None:
    """Largest of ``errors[condition][quantity]`` (percent); None if any is missing (None).

    A quantity absent from a condition's errors is left out."""
    qs = [q] if q else [k for k, _, _ in QUANTITIES]
    vals = [errors[c][k] for c in errors for k in qs if k in errors[c]]
    if not errors or not vals or any(v is None or not math.isfinite(v) for v in vals):
        return None
    return max(vals)


def _relative(
    a: float | None, b: float | None, out: dict[str, float | None], q: str, scale: float = 0.0
) -> None:
    """``out[q]`` = |a - b| / |b| in percent; None if a value is missing. Where b is 0 (a
    damper stuck at the peak dissipates nothing) no error is relative to it: 0 % if ``a``
    is 0 too, else |a| in percent of ``scale`` (the largest |b| of the quantity over the
    study's conditions: a slip where the reference sticks counts by its size against the
    energies the study measures), 100 % without a scale. Round-off zeros count as 0
    (``ROUND_OFF_ZERO``)."""
    a, b = zeroed(q, a), zeroed(q, b)
    if a is None or b is None:
        out[q] = None
    elif b != 0:
        out[q] = abs(a - b) / abs(b) * 100.0
    elif a == 0:
        out[q] = 0.0
    else:
        out[q] = abs(a) / scale * 100.0 if scale > 0 else 100.0


def _scales(values: dict[str, dict[str, float | None]]) -> dict[str, float]:
    """quantity -> the largest |value| over the conditions (0 if none)."""
    return {
        q: max([abs(v[q]) for v in values.values() if v.get(q) is not None] or [0.0])
        for q, _, _ in QUANTITIES
    }


def condition_name(phase: float, force: float, damper: str | None = None) -> str:
    """A condition's name: '0 deg 30 N', or 'cone 0 deg 30 N' in a study of several dampers."""
    return f"{damper + ' ' if damper else ''}{phase:g} deg {force:g} N"


def relative_errors(st: Setting, ref: Setting) -> dict[str, dict[str, float | None]]:
    """condition -> quantity -> |q - q_ref| / |q_ref| in percent (None: no value to compare;
    against a q_ref of 0: see :func:`_relative`)."""
    out: dict[str, dict[str, float | None]] = {}
    peaks = {c: r.refined_peak() for c, r in ref.results.items() if not r.branch.failed}
    scale = _scales(peaks)
    for cond, r in st.results.items():
        s = r.refined_peak() if not r.branch.failed else {}
        sr = peaks.get(cond, {})
        out[cond] = {}
        for q, _, _ in QUANTITIES:
            _relative(s.get(q), sr.get(q), out[cond], q, scale[q])
    return out


def ladder_self_errors(ladders: dict[str, list[Setting]]) -> dict[str, list[float | None]]:
    """knob -> worst error (percent) of each level against the knob's OWN finest level.

    The other knobs stay at the base in both, so this is the error that knob
    alone makes (its convergence), free of the other knobs' errors that every
    one-knob setting carries against the reference.
    """
    return {
        knob: [worst(relative_errors(st, lad[-1])) for st in lad] for knob, lad in ladders.items()
    }


# knobs whose every level meshes the model anew (the contact points are mesh nodes): their
# ladders cannot resolve differences below the re-meshing scatter the mesh ladder measures
REMESHING_KNOBS = ("contact-mesh-size", "points-per-line")
# ... and the mesh ladder, whose bands are no narrower than its own scatter either (that
# scatter bounds only the other knobs' oscillations: it cannot vouch for its own ladder)
REMESHES = ("mesh-size", *REMESHING_KNOBS)
NO_LADDER = "no fineness to extrapolate"  # the reason given for a modelling choice (rigid damper)
# the reason given where a knob does not reach a condition's model (points per line: the wedge)
NOT_APPLICABLE = "the knob does not reach this damper's model"


def knob_h(knob: str, v: Any) -> float | None:
    """The fineness h of one knob level (smaller is finer) for Richardson extrapolation.

    mesh size and contact mesh size: the size in mm; modes: 1/modes; harmonics: 1/H of the highest
    harmonic H; nt: 1/nt; points per line: 1/points. None for the rigid/flexible
    damper, which is no ladder of a fineness.
    """
    if knob in ("mesh-size", "contact-mesh-size"):
        return float(v)
    if knob == "harmonics":
        return 1.0 / max(v) if max(v) > 0 else None
    if knob in ("modes", "nt", "points-per-line"):
        return 1.0 / int(v) if v else None
    return None


def is_ladder(knob: str, lad: list[Setting]) -> bool:
    """Whether a knob's levels have a fineness (a ladder towards a limit), not a choice."""
    return all(knob_h(knob, st.values[knob]) is not None for st in lad)


def setting_value(st: Setting, cond: str, q: str) -> float | None:
    """Quantity ``q`` of setting ``st`` at condition ``cond``; None if missing, failed or
    not finite. The peak between the computed points (``CaseResult.refined_peak``): the
    highest computed point alone moves by up to half a step from level to level, which
    no ladder should read as convergence."""
    r = st.results.get(cond)
    if r is None or r.branch.failed:
        return None
    v = r.refined_peak().get(q)
    return None if v is None or not math.isfinite(v) else zeroed(q, float(v))


def setting_resolution(st: Setting, cond: str, q: str) -> float | None:
    """How finely setting ``st``'s curve at ``cond`` resolves quantity ``q`` (its units;
    ``CaseResult.peak_resolution``); None if unknown."""
    r = st.results.get(cond)
    if r is None or r.branch.failed:
        return None
    v = r.peak_resolution().get(q)
    return None if v is None or not math.isfinite(v) else float(v)


def ladder_limits(
    ladders: dict[str, list[Setting]], skip: set[tuple[str, str]] | frozenset = frozenset()
) -> dict[str, dict[str, dict[str, Any]]]:
    """knob -> condition -> quantity -> :class:`LimitEstimate` from the knob's finest levels.

    Each knob's ladder (the other knobs at the base) is extrapolated with the
    observed order (``workbench.post.extrapolation.richardson``), given the
    quantity's resolution on the finest three levels' curves
    (:func:`setting_resolution`, the largest): differences within it bound the
    limit instead. A knob that re-meshes (``REMESHES``) also gets the re-meshing
    scatter of :func:`remeshing_scatter`: finest levels that oscillate within it are
    bounded by it, and none of its bands is narrower. A knob with
    no fineness (rigid damper) or two levels only falls back to its finest
    level, flagged not asymptotic. ``skip``: the (knob, condition) pairs where
    the knob does not reach the condition's model (points per line on the
    wedge): the finest level's value, method "not applicable", which
    :func:`combined_limits` leaves out (no correction, no flag).
    """
    out: dict[str, dict[str, dict[str, Any]]] = {}
    remesh = remeshing_scatter(ladders)
    for knob, lad in ladders.items():
        ladder = is_ladder(knob, lad)
        hs = [knob_h(knob, st.values[knob]) for st in lad]
        if ladder:
            # levels of one fineness ("H 1" and "H 0-1": the same highest harmonic) are
            # no ladder step: the finer one (later in the coarse-to-fine ladder) is kept
            last = {h: i for i, h in enumerate(hs)}
            keep = sorted(last.values())
            lad, hs = [lad[i] for i in keep], [hs[i] for i in keep]
        out[knob] = {}
        for cond in lad[-1].results:
            out[knob][cond] = {}
            for q, _, _ in QUANTITIES:
                vals = [setting_value(st, cond, q) for st in lad]
                if (knob, cond) in skip:
                    v = vals[-1]
                    est = LimitEstimate(
                        v, None, None, False, "not applicable", NOT_APPLICABLE, v, 0
                    )
                elif ladder:
                    res = [setting_resolution(st, cond, q) for st in lad]
                    finest3 = sorted(
                        (h, r) for h, r, v in zip(hs, res, vals, strict=True) if v is not None
                    )[:3]
                    known = [r for _, r in finest3 if r is not None]
                    sc = remesh.get((cond, q)) if knob in REMESHES else None
                    est = richardson(
                        hs, vals, noise=max(known) if known else None,
                        scatter=sc if knob in REMESHING_KNOBS else None,  # not its own
                    )  # fmt: skip
                    if sc and est.trusted and est.uncertainty < SAFETY * sc:
                        est = replace(est, uncertainty=SAFETY * sc, reason=(
                            f"{est.reason}; widened to the re-meshing scatter {sc:.3g} "
                            f"(x {SAFETY:g})").lstrip("; "))  # fmt: skip
                else:
                    v = vals[-1]
                    est = LimitEstimate(v, None, None, False, "finest level", NO_LADDER, v, 1)
                out[knob][cond][q] = est
    return out


def remeshing_scatter(ladders: dict[str, list[Setting]]) -> dict[tuple[str, str], float]:
    """(condition, quantity) -> the scatter of the global mesh ladder about its trend
    (:func:`~workbench.post.extrapolation.fit_scatter`; four or more levels with a value).

    An unstructured mesh places its nodes anew at every setting, so a value moves by
    about this much whenever the model is meshed again, whatever is refined: a knob that
    re-meshes (``REMESHING_KNOBS``) cannot resolve less, and :func:`ladder_limits` gives
    it as that knob's noise floor. Empty without a mesh-size ladder of four levels."""
    lad = ladders.get("mesh-size")
    if not lad or not is_ladder("mesh-size", lad):
        return {}
    out: dict[tuple[str, str], float] = {}
    for cond in lad[-1].results:
        for q, _, _ in QUANTITIES:
            pts = [(knob_h("mesh-size", st.values["mesh-size"]), setting_value(st, cond, q))
                   for st in lad]  # fmt: skip
            pts = [(h, v) for h, v in pts if v is not None]
            sc = fit_scatter([h for h, _ in pts], [v for _, v in pts])
            if sc is not None:
                out[(cond, q)] = sc
    return out


def combined_limits(
    ref: Setting, ladders: dict[str, list[Setting]], limits: dict[str, dict[str, dict[str, Any]]]
) -> dict[str, dict[str, dict[str, Any]]]:
    """condition -> quantity -> the limit of every knob at once, around the reference.

    Assumes the knobs' errors add (first order): the limit is the reference's
    value plus, per knob, its extrapolated limit minus its finest level's
    value (both with the other knobs at the base). The uncertainty is the sum
    of the knobs' (conservative). ``asymptotic`` is True only if every knob's
    is; ``trusted`` if every knob's limit is extrapolated or bounded (a
    bounded knob, ``bounded`` lists them, adds no correction but its bound to
    the uncertainty); a knob that falls back untrusted adds no correction and
    no known uncertainty, so the uncertainty is then None. A knob whose finest level is not the
    reference's value (the base is finer) cannot be used: flagged too. A knob
    that is no discretisation (the rigid or flexible damper: a modelling
    choice, no fineness) has no limit: the reference's choice stands and it
    neither corrects nor flags the limit.
    """
    out: dict[str, dict[str, dict[str, Any]]] = {}
    for cond in ref.results:
        out[cond] = {}
        for q, _, _ in QUANTITIES:
            v = setting_value(ref, cond, q)
            unc: float | None = 0.0
            asym, why = v is not None, [] if v is not None else ["no reference value"]
            trusted = asym
            bound: list[str] = []
            orders: dict[str, float | None] = {}
            for knob, lad in ladders.items():
                if not is_ladder(knob, lad):
                    continue  # a modelling choice, not a ladder towards a limit
                est = limits[knob].get(cond, {}).get(q)
                if est is not None and est.method == "not applicable":
                    continue  # the knob does not reach this condition's model
                orders[knob] = est.order if est is not None else None
                if lad[-1].values[knob] != ref.values[knob]:
                    asym, trusted, unc = False, False, None
                    why.append(f"{knob}: the base is finer than its levels")
                    continue
                if est is not None and est.finest != setting_value(lad[-1], cond, q):
                    est = None  # the finest level failed: its correction has no anchor
                if est is None or not est.trusted:
                    asym, trusted, unc = False, False, None
                    why.append(f"{knob}: {est.reason if est is not None else 'no value'}")
                    continue
                if not est.asymptotic:  # bounded or fitted: no longer asymptotic
                    asym = False
                    bound.append(knob)
                if est.corrects and v is not None:  # bounded: no correction, only its band
                    v += est.value - est.finest
                if unc is not None:
                    unc += est.uncertainty
            out[cond][q] = {
                "value": v,
                "uncertainty": unc,
                "asymptotic": asym,
                "trusted": trusted,
                "bounded": bound,
                "orders": orders,
                "reason": "; ".join(why),
            }
    return out


def limit_errors(st: Setting, combined: dict[str, dict[str, dict[str, Any]]]) -> dict:
    """condition -> quantity -> |q - q_lim| / |q_lim| in percent (None: nothing to compare)."""
    out: dict[str, dict[str, float | None]] = {}
    scale = _scales({c: {q: d.get("value") for q, d in qs.items()} for c, qs in combined.items()})
    for cond in st.results:
        out[cond] = {}
        for q, _, _ in QUANTITIES:
            a, lim = setting_value(st, cond, q), combined.get(cond, {}).get(q, {}).get("value")
            _relative(a, lim, out[cond], q, scale.get(q, 0.0))
    return out


def pick_error(st: Setting, combined: dict[str, dict[str, dict[str, Any]]]) -> float | None:
    """The worst error (percent) the tolerance pick judges ``st`` by: against the
    all-knob limit where that limit is trusted (``trusted``), against the reference
    elsewhere (the limit of that condition and quantity is not known). None if any error
    is missing."""
    errs: dict[str, dict[str, float | None]] = {}
    for cond in st.results:
        errs[cond] = {}
        for q, _, _ in QUANTITIES:
            trusted = combined.get(cond, {}).get(q, {}).get("trusted")
            src = (st.limit_errors if trusted else st.errors).get(cond, {})
            if q in src or cond not in (st.limit_errors if trusted else st.errors):
                errs[cond][q] = src.get(q)
    return worst(errs)


def pick_basis(combined: dict[str, dict[str, dict[str, Any]]]) -> str:
    """In words, what :func:`pick_error` measures against."""
    trusted = sorted({f"{q} at {c}" for c, qs in combined.items() for q, e in qs.items()
                      if e.get("trusted")})  # fmt: skip
    if not trusted:
        return "errors against the reference (no extrapolated limit is trusted)"
    listed = ", ".join(trusted)
    return f"errors against the extrapolated limit for {listed}; against the reference elsewhere"


def limit_uncertainty_pct(combined: dict[str, dict[str, dict[str, Any]]], q: str) -> float | None:
    """The largest uncertainty of the limit of ``q`` over the conditions, percent of |limit|
    (None if one is unknown); a limit of 0 (a stuck damper's energy) has none and is left out."""
    us = []
    for c in combined.values():
        d = c.get(q, {})
        if d.get("value") == 0.0 and d.get("uncertainty") is not None:
            continue  # a known zero (stuck): no relative band
        if d.get("uncertainty") is None or not d.get("value"):
            return None
        us.append(abs(d["uncertainty"]) / abs(d["value"]) * 100.0)
    return max(us) if us else None


def setting_row(st: Setting) -> dict[str, Any]:
    row: dict[str, Any] = {
        "label": st.label,
        "role": st.role,
        "knobs": "; ".join(f"{k}={m}" for k, m in st.members),
    }
    for k in KNOBS:
        row[k] = level_label(k, st.values[k])
    for s in STAGES:
        row[f"{s}_s"] = round(st.times.get(s, 0.0), 3)
    row["time_s"] = round(st.time_s, 3)
    for q, _, _ in QUANTITIES:
        e = st.error(q)
        row[f"err_{q}_pct"] = e
    row["max_error_pct"] = st.error()
    for q, _, _ in QUANTITIES:
        row[f"err_lim_{q}_pct"] = st.limit_error(q)
    row["max_error_vs_limit_pct"] = st.limit_error()
    row["failed"] = "; ".join(st.failed)
    return row

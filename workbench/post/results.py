"""The results of a study: one frequency-response branch per case, plus what frames it.

A *case* is one damper, one inter-blade phase angle, one excitation level
and one set of modelling knobs (its ``variant`` label; "" for the study's
base settings). Its :class:`~workbench.hbm.forced.branch.Branch` holds the curve
(frequency, response amplitude, stability, contact status and friction
energy of every pair at every point).

Units: the branch is SI (m, J); the accessors here convert to the units
the study reports in: amplitude in mm, energy per cycle in mJ, frequency
in Hz, force in N.

Status codes of a contact pair over one period::

    0 stuck            never slips, never separates
    1 stick-slip       slips during part of the period, never separates
    2 partial sep.     separates during part of the period
    3 full separation  open during the whole period
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..hbm.forced.branch import Branch
from ..io import atomic_path

STATUS_NAMES = ("stuck", "stick-slip", "partial separation", "full separation")
STATUS_KEYS = ("stuck", "stick_slip", "partial_separation", "full_separation")
# below this friction energy per cycle (mJ) a loop is the time sampling's round-off (the
# stuck wedge's -0.001 mJ on the paper rig), and its split between the lines means nothing
SPLIT_FLOOR_MJ = 1e-3


def family_name(phase_deg: float) -> str:
    """'in-phase' (0 deg), 'out-of-phase' (180 deg) or 'phase N deg'."""
    p = float(phase_deg) % 360.0
    if abs(p) < 1e-9 or abs(p - 360.0) < 1e-9:
        return "in-phase"
    if abs(p - 180.0) < 1e-9:
        return "out-of-phase"
    return f"phase {p:g} deg"


def case_id(case) -> str:
    """File-name id of a case (a plan Case or a CaseResult): damper-phase-force[-variant]."""
    v = f"-{case.variant}" if case.variant else ""
    return f"{case.damper}-{case.phase_deg:g}deg-{case.force_n:g}N{v}".replace("=", "")


_PEAK_KEYS = ("peak_frequency_hz", "peak_amplitude_mm", "friction_energy_mj")


@dataclass
class CaseResult:
    """One computed case and its frame (damper, phase, force, knobs, contact layout)."""

    damper: str
    phase_deg: float
    force_n: float
    branch: Branch
    points: np.ndarray  # (n_pairs, 3) m, contact pair coordinates
    side: np.ndarray  # (n_pairs,) 0/1
    variant: str = ""  # "" for the base settings, else e.g. "modes=24"
    params: dict[str, Any] = field(default_factory=dict)  # the case's canonical parameters
    digest: str = ""
    timings: dict[str, float] = field(default_factory=dict)  # stage -> s (incl. shared stages)
    output: int = 0  # index of the reported output in the branch
    # every input the solve used: key -> {value, unit, source, label, group} (post/provenance.py)
    inputs: dict[str, dict[str, Any]] = field(default_factory=dict)

    @property
    def case_id(self) -> str:
        return case_id(self)

    @property
    def family(self) -> str:
        return family_name(self.phase_deg)

    # ---- curves in report units
    @property
    def freq_hz(self) -> np.ndarray:
        return self.branch.freq_hz

    @property
    def amp_mm(self) -> np.ndarray:
        """Largest response displacement over the period at each point, max |x(t)|, mm
        (the mean term included)."""
        return self.branch.out_amp[:, self.output] * 1e3

    @property
    def receptance_mm_per_n(self) -> np.ndarray:
        """max |x(t)| / F at each point, mm/N."""
        return self.amp_mm / self.force_n

    @property
    def h1_mm(self) -> np.ndarray:
        """Harmonic-1 amplitude of the response at each point, mm: the vibration, without
        the mean term and the higher harmonics (the report's amplitude)."""
        return self.branch.out_h1[:, self.output] * 1e3

    @property
    def h1_receptance_mm_per_n(self) -> np.ndarray:
        """Harmonic-1 amplitude / F at each point, mm/N."""
        return self.h1_mm / self.force_n

    @property
    def mean_mm(self) -> np.ndarray:
        """The mean term (harmonic 0) of the response at each point, mm (0 when the balance
        has no harmonic 0)."""
        b = self.branch
        row = 0
        for h in b.harmonics:
            if h == 0:
                return np.asarray(b.out_harm)[:, row, self.output] * 1e3
            row += 2
        return np.zeros(b.n_points)

    @property
    def h1_peak_index(self) -> int:
        """Index of the point of largest harmonic-1 amplitude (-1 without points)."""
        return int(np.argmax(self.h1_mm)) if self.branch.n_points else -1

    @property
    def h1_peak_covered(self) -> bool:
        """True when the harmonic-1 peak lies strictly inside a curve that completed."""
        j, n = self.h1_peak_index, self.branch.n_points
        return bool(self.branch.completed and not self.branch.failed and 0 < j < n - 1)

    @property
    def stable(self) -> np.ndarray:
        return self.branch.stable

    @property
    def peak_index(self) -> int:
        return self.branch.peak(self.output)

    @property
    def peak_covered(self) -> bool:
        """True when the curve shows its resonance peak.

        That is: the curve reached the end of its band without failing and
        its highest point lies strictly inside it. Otherwise (a curve
        stopped by ``max-points``, a failed solve, a band that ends before
        the resonance) the highest computed point is only a *lower bound*
        of the peak, and :meth:`summary` reports it as such, never as the
        peak.
        """
        i, n = self.peak_index, self.branch.n_points
        return bool(self.branch.completed and not self.branch.failed and 0 < i < n - 1)

    def peak_note(self) -> str:
        """Why the peak is a lower bound ("" when it is covered)."""
        if self.peak_covered:
            return ""
        i = self.peak_index
        if i < 0:
            return "no point computed: no peak"
        f, a = float(self.freq_hz[i]), float(self.amp_mm[i])
        if self.branch.completed and not self.branch.failed:
            where = (
                f"the highest point is at the band edge ({f:.6g} Hz): the resonance lies "
                "outside the band"
            )
        else:
            why = self.branch.message or "stopped early"
            where = (
                f"the curve stopped at {float(self.freq_hz[-1]):.6g} Hz before covering its "
                f"resonance ({why})"
            )
        return f"{where}; {a:.4g} mm is only a lower bound of the peak"

    @property
    def energy_mj(self) -> np.ndarray:
        """(n_points, n_pairs) friction energy per cycle of every pair, mJ."""
        return self.branch.friction_energy * 1e3

    def energy_split_pct(self, i: int | None = None) -> float | None:
        """The friction energy per cycle of platform 1's pairs minus platform 2's, in percent
        of their sum, at point ``i`` (default: the harmonic-1 peak). The two-blade rig and
        its in- and out-of-phase loading are symmetric about the plane between the blades,
        so a symmetric solution splits evenly (0); a mesh whose halves differ tips it
        (docs/notes/mesh_symmetry.md). None where the contact does not slip (the energy is
        at most :data:`SPLIT_FLOOR_MJ`) or there is no point."""
        i = self.h1_peak_index if i is None else i
        if i < 0:
            return None
        e = self.energy_mj[i]
        e1, e2 = float(e[self.side == 0].sum()), float(e[self.side == 1].sum())
        total = e1 + e2
        return None if total <= SPLIT_FLOOR_MJ else (e1 - e2) / total * 100.0

    def status_shares(self, i: int | None = None) -> dict[str, float]:
        """Fraction of pairs in each status at point ``i`` (default: the resonance, the
        harmonic-1 peak)."""
        i = self.h1_peak_index if i is None else i
        if i < 0:
            return {k: float("nan") for k in STATUS_KEYS}
        counts = np.bincount(self.branch.status[i].astype(int), minlength=4)[:4]
        total = max(1, int(counts.sum()))
        return {k: float(c) / total for k, c in zip(STATUS_KEYS, counts, strict=True)}

    def summary(self) -> dict[str, Any]:
        """The per-case numbers of the study's JSON summary and tables."""
        i = self.peak_index
        ok = i >= 0
        out = {
            "case": self.case_id,
            "damper": self.damper,
            "phase_deg": self.phase_deg,
            "family": self.family,
            "force_n": self.force_n,
            "variant": self.variant,
            "peak_frequency_hz": float(self.freq_hz[i]) if ok else None,
            "peak_amplitude_mm": float(self.amp_mm[i]) if ok else None,
            # the harmonic-1 peak, at its own frequency: the vibration without the mean
            # (a stuck damper's mean position depends on its history, and it shifts max|x|)
            **self._h1_peak(),
            **self._energy_at(i),
            "peak_stable": bool(self.stable[i]) if ok else None,
            "n_points": self.branch.n_points,
            "n_stable": int(np.sum(self.branch.stability == 1)),
            "n_unstable": int(np.sum(self.branch.unstable)),
            "n_stability_unknown": int(np.sum(self.branch.unknown)),
            "n_stable_carried": int(np.sum(self.branch.stability == 2)),
            "n_unstable_carried": int(np.sum(self.branch.stability == 3)),
            "n_hill_checks": int(np.sum(self.branch.stability_how == 1)),
            "energy_residual_max": float(np.max(self.branch.energy_residual)) if ok else None,
            "accuracy_max": self.branch.summary(self.output)["accuracy_max"],
            "peak_stability": self.branch.stability_name(i) if ok else None,
            "completed": bool(self.branch.completed),
            "message": self.branch.message,
            "wall_s": round(
                float(self.timings.get("hbm", self.branch.timings.get("total", 0.0))), 3
            ),
        }
        out.update({f"share_{k}": v for k, v in self.status_shares().items()})
        out.update(self._peak_bound())
        return out

    def _peak_point(self) -> dict[str, float | None]:
        """The summary's peak values (the highest computed point; None where the curve does
        not cover its peak, :attr:`peak_covered`) without computing the rest of it."""
        if not self.peak_covered:
            return dict.fromkeys(_PEAK_KEYS)
        i = self.peak_index
        return {
            "peak_frequency_hz": float(self.freq_hz[i]),
            "peak_amplitude_mm": float(self.amp_mm[i]),
            "friction_energy_mj": self._energy_at(i)["friction_energy_mj"],
        }

    def refined_peak(self) -> dict[str, float | None]:
        """The peak between the computed points: the vertex of the parabola a(f) through
        the highest point and its two neighbours, and the frequency and the friction energy
        (a parabola in f too) there. The summary's values where that gives no inner
        maximum: an edge point, a fold at the top (f not monotone over the three points),
        a curve that is not concave there."""
        out = self._peak_point()
        if out["peak_amplitude_mm"] is None:  # not covered: no inner highest point
            return out
        i = self.peak_index
        j = np.array([i - 1, i, i + 1])
        f, a = self.freq_hz[j], self.amp_mm[j]
        df = np.diff(f)
        if not (np.all(df > 0) or np.all(df < 0)):
            return out
        ca = np.polyfit(f - f[1], a, 2)
        if ca[0] >= 0:
            return out
        t = float(np.clip(-ca[1] / (2 * ca[0]), min(f) - f[1], max(f) - f[1]))
        out["peak_amplitude_mm"] = float(np.polyval(ca, t))
        out["peak_frequency_hz"] = float(f[1] + t)
        if out["friction_energy_mj"] is not None:
            e = np.array([float(self.energy_mj[k].sum()) for k in j])
            out["friction_energy_mj"] = max(0.0, float(np.polyval(np.polyfit(f - f[1], e, 2), t)))
        return out

    def peak_resolution(self) -> dict[str, float | None]:
        """How finely the computed points resolve the peak, per summary quantity (units).

        Where :meth:`refined_peak` placed the peak between the points, the distance it
        moved each quantity from the highest computed point: the interpolation's own
        error is of the order of that correction (smaller on a smooth peak, as large on
        a kinked one). Elsewhere the highest point's own resolution: half the step to a
        neighbour in frequency, the rise a parabola through the three points could add
        to the amplitude (``(2 a_i - a_{i-1} - a_{i+1}) / 8``, exact at equal steps), half
        the energy's change to a neighbour. None where the peak has no neighbour on both
        sides (an edge point: not covered).
        """
        i, n = self.peak_index, self.branch.n_points
        if i <= 0 or i >= n - 1:
            return dict.fromkeys(_PEAK_KEYS)
        top, at = self.refined_peak(), self._peak_point()
        if top["peak_frequency_hz"] != at["peak_frequency_hz"]:
            return {
                k: None if top[k] is None or at[k] is None else abs(top[k] - at[k])
                for k in _PEAK_KEYS
            }
        f, a = self.freq_hz, self.amp_mm
        e = [float(self.energy_mj[j].sum()) for j in (i - 1, i, i + 1)]
        return {
            "peak_frequency_hz": 0.5 * float(max(abs(f[i + 1] - f[i]), abs(f[i] - f[i - 1]))),
            "peak_amplitude_mm": max(0.0, float(2 * a[i] - a[i - 1] - a[i + 1]) / 8.0),
            "friction_energy_mj": 0.5 * max(abs(e[2] - e[1]), abs(e[1] - e[0])),
        }

    def _energy_at(self, i: int) -> dict[str, Any]:
        """Friction energy per cycle at point ``i``; a negative loop integral (time
        sampling of a nearly closed loop: dissipation cannot be negative) is reported
        as 0 with a note that gives the computed value."""
        if i < 0:
            return {"friction_energy_mj": None, "friction_energy_note": ""}
        e = float(self.energy_mj[i].sum())
        if e >= 0:
            return {"friction_energy_mj": e, "friction_energy_note": ""}
        return {
            "friction_energy_mj": 0.0,
            "friction_energy_note": (
                f"the loop integral came out {e:.2e} mJ (time sampling of loops that hardly "
                "open); dissipation cannot be negative: reported as 0 (stuck)"
            ),
        }

    def _h1_peak(self) -> dict[str, Any]:
        """The harmonic-1 peak and, at that same point, max |x(t)|, the mean term, the
        friction energy and the stability verdict (None where there is no point)."""
        j = self.h1_peak_index
        if j < 0:
            keys = ("amplitude_mm", "peak_frequency_hz", "max_abs_mm", "mean_mm")
            keys += ("friction_energy_mj", "friction_energy_note", "friction_energy_split_pct")
            keys += ("peak_stability",)
            return {f"h1_{k}": None for k in keys}
        e = self._energy_at(j)
        return {
            "h1_amplitude_mm": float(self.h1_mm[j]),
            "h1_peak_frequency_hz": float(self.freq_hz[j]),
            "h1_max_abs_mm": float(self.amp_mm[j]),
            "h1_mean_mm": float(self.mean_mm[j]),
            "h1_friction_energy_mj": e["friction_energy_mj"],
            "h1_friction_energy_note": e["friction_energy_note"],
            "h1_friction_energy_split_pct": self.energy_split_pct(j),
            "h1_peak_stability": self.branch.stability_name(j),
        }

    def _peak_bound(self) -> dict[str, Any]:
        """Summary keys saying whether the peak was reached; a peak the curve did not reach
        is never reported as one: its values are None and its amplitude a lower bound."""
        i, covered = self.peak_index, self.peak_covered
        j = self.h1_peak_index
        out: dict[str, Any] = {
            "peak_covered": covered,
            "peak_lower_bound_mm": None,
            "peak_note": self.peak_note(),
            "h1_peak_covered": self.h1_peak_covered,
            "h1_lower_bound_mm": None,
        }
        if not covered and i >= 0:
            out["peak_lower_bound_mm"] = float(self.amp_mm[i])
            for k in (
                "peak_frequency_hz",
                "peak_amplitude_mm",
                "friction_energy_mj",
                "friction_energy_note",
                "peak_stable",
                "peak_stability",
            ):
                out[k] = None
        if not self.h1_peak_covered and j >= 0:
            out["h1_lower_bound_mm"] = float(self.h1_mm[j])
            for k in ("amplitude_mm", "peak_frequency_hz", "max_abs_mm", "mean_mm"):
                out[f"h1_{k}"] = None
            for k in ("friction_energy_mj", "friction_energy_note", "peak_stability"):
                out[f"h1_{k}"] = None
        return out

    # ---- storage
    def save(self, path: str | Path) -> Path:
        """Write the case (its branch plus frame) to one HDF5 file atomically."""
        import h5py

        path = Path(path)
        # the branch and the frame go into one temporary file, renamed over ``path`` at
        # the end: a run killed in between never leaves a case file without its frame
        with atomic_path(path) as tmp:
            self.branch.save(tmp)
            with h5py.File(tmp, "a") as h:
                g = h.require_group("case")
                g["points"] = self.points
                g["side"] = self.side
                a = g.attrs
                a["damper"], a["phase_deg"] = self.damper, self.phase_deg
                a["force_n"] = self.force_n
                a["variant"], a["digest"], a["output"] = self.variant, self.digest, self.output
                a["params"] = json.dumps(self.params, default=str, sort_keys=True)
                a["timings"] = json.dumps(self.timings)
                if self.inputs:
                    from .provenance import save_inputs

                    save_inputs(g.create_group("inputs"), self.inputs)
                from ..io.units import BRANCH_UNITS, CASE_UNITS, annotate

                annotate(h, {**BRANCH_UNITS, **CASE_UNITS})
        return path

    @classmethod
    def load(cls, path: str | Path) -> CaseResult:
        import h5py

        branch = Branch.load(path)
        with h5py.File(path, "r") as h:
            g = h["case"]
            a = g.attrs
            return cls(
                damper=str(a["damper"]),
                phase_deg=float(a["phase_deg"]),
                force_n=float(a["force_n"]),
                branch=branch,
                points=g["points"][()],
                side=g["side"][()],
                variant=str(a["variant"]),
                digest=str(a["digest"]),
                output=int(a["output"]),
                params=json.loads(a["params"]),
                timings=json.loads(a["timings"]),
                inputs=_inputs_of(g),
            )


@dataclass
class StudyResults:
    """Every case of a study, in plan order, and what the study computed besides them."""

    name: str
    kind: str
    cases: list[CaseResult]
    inputs: dict[str, Any] = field(default_factory=dict)
    extras: dict[str, Any] = field(default_factory=dict)  # e.g. linear frequencies per damper
    timings: dict[str, float] = field(default_factory=dict)

    def select(
        self,
        *,
        damper: str | None = None,
        phase_deg: float | None = None,
        force_n: float | None = None,
        variant: str | None = None,
    ) -> list[CaseResult]:
        """The cases matching every given key (floats compared to 1e-9)."""
        out = []
        for c in self.cases:
            if damper is not None and c.damper != damper:
                continue
            if phase_deg is not None and abs(c.phase_deg - phase_deg) > 1e-9:
                continue
            if force_n is not None and abs(c.force_n - force_n) > 1e-9:
                continue
            if variant is not None and c.variant != variant:
                continue
            out.append(c)
        return out

    @property
    def dampers(self) -> list[str]:
        return list(dict.fromkeys(c.damper for c in self.cases))

    @property
    def phases(self) -> list[float]:
        return list(dict.fromkeys(c.phase_deg for c in self.cases))

    @property
    def forces(self) -> list[float]:
        return sorted(set(c.force_n for c in self.cases))

    def summaries(self) -> list[dict[str, Any]]:
        return [c.summary() for c in self.cases]

    def uncovered(self) -> list[CaseResult]:
        """The cases whose curve did not cover the resonance peak (failed ones included)."""
        return [c for c in self.cases if not c.peak_covered]

    def save(self, path: str | Path) -> Path:
        """All cases in one HDF5 file: /cases/<case_id>/... plus attributes."""
        import tempfile

        import h5py

        path = Path(path)
        with (
            tempfile.TemporaryDirectory() as scratch,
            atomic_path(path) as tmp,
            h5py.File(tmp, "w") as h,
        ):
            h.attrs["name"], h.attrs["kind"] = self.name, self.kind
            h.attrs["inputs"] = json.dumps(self.inputs, default=str)
            h.attrs["extras"] = json.dumps(self.extras, default=_np_default)
            h.attrs["timings"] = json.dumps(self.timings)
            h.attrs["order"] = json.dumps([c.case_id for c in self.cases])
            for k, c in enumerate(self.cases):
                one = c.save(Path(scratch) / f"{k}.h5")
                with h5py.File(one, "r") as src:
                    src.copy(src["/"], h, name=f"cases/{c.case_id}")
        return path

    @classmethod
    def load(cls, path: str | Path) -> StudyResults:
        """Read a file written by :meth:`save`."""
        import tempfile

        import h5py

        cases = []
        with h5py.File(path, "r") as h, tempfile.TemporaryDirectory() as scratch:
            a = h.attrs
            for k, cid in enumerate(json.loads(a["order"])):
                one = Path(scratch) / f"{k}.h5"
                with h5py.File(one, "w") as dst:
                    for name in h[f"cases/{cid}"]:
                        h.copy(h[f"cases/{cid}/{name}"], dst, name=name)
                    for key, val in h[f"cases/{cid}"].attrs.items():
                        dst.attrs[key] = val
                cases.append(CaseResult.load(one))
            return cls(
                name=str(a["name"]),
                kind=str(a["kind"]),
                cases=cases,
                inputs=json.loads(a["inputs"]),
                extras=json.loads(a["extras"]),
                timings=json.loads(a["timings"]),
            )


def _inputs_of(group: Any) -> dict[str, dict[str, Any]]:
    if "inputs" not in group:  # a case solved before the inputs were recorded
        return {}
    from .provenance import load_inputs

    return load_inputs(group["inputs"])


def _np_default(o: Any) -> Any:
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, np.generic):
        return o.item()
    return str(o)

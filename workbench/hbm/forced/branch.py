"""The result of a frequency response: a branch of periodic solutions, saved to HDF5.

Per point ``i`` (in continuation order, so a curve that turns back keeps
its order): ``freq_hz[i]``; ``stability[i]`` (Hill's verdict: 1 stable,
0 unstable, -1 unknown: not computed, eigen-solver failure or a failed
count check; 2 and 3: stable or unstable carried from checked neighbours,
not established at the point, see :mod:`..stability.along_path`),
``stability_how[i]`` (0 not computed, 1 Hill's method at the point, 2 every
contact stuck: the linear system's verdict, 3 carried) and ``stable[i]``
(True only for an established stable verdict; use :attr:`Branch.unstable`,
:attr:`Branch.unknown` and :attr:`Branch.carried` for the others); ``newton_its[i]``;
``energy_residual[i]`` (relative, work of the excitation against viscous +
contact work per cycle); ``accuracy[i]`` (the loop-energy vs harmonic-work
mismatch, a fraction of the excitation work: it grows when ``nt`` or the
harmonics do not resolve the contact loops, see :mod:`..core.balance`);
``out_amp[i, j]`` the largest ``|y_j(t)|`` over the period and
``out_h1[i, j]`` the harmonic-1 amplitude of output ``j`` (model length
unit); ``out_harm[i]`` (nh, n_out) the output harmonics;
``status[i, e]`` (0 stuck, 1 stick-slip, 2 partial separation, 3 full
separation); ``friction_energy[i, e]`` (J per cycle); ``x[i]`` the solved
unknowns (m; the layout of :mod:`..core.balance`), from which
``HarmonicBalance.response`` recovers every DOF.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from ...io.record import Layout, PathRecord

_ARRAYS = (
    "freq_hz",
    "stable",
    "stability",
    "stability_how",
    "newton_its",
    "energy_residual",
    "out_amp",
    "out_h1",
    "out_rms",
    "out_harm",
    "status",
    "friction_energy",
    "x",
    "work_ext",
    "work_visc",
    "work_friction",
    "work_normal",
    "max_floquet_real",
    "accuracy",
)
LAYOUT = Layout(
    datasets=_ARRAYS,
    attrs=(
        ("level", "float"),
        ("band_hz", "floats"),
        ("harmonics", "ints"),
        ("nt", "int"),
        ("output_names", "names"),
        ("space", "str"),
        ("completed", "bool"),
        ("failed", "bool"),
        ("message", "str"),
        ("label", "str"),
        ("timings", "json"),
        ("stats", "json"),
        ("options", "json"),
    ),
)


@dataclass
class Branch(PathRecord):
    """A computed frequency response curve (see the module docstring for the arrays)."""

    level: float
    band_hz: tuple[float, float]
    harmonics: tuple[int, ...]
    nt: int
    output_names: tuple[str, ...]
    space: str = "condensed"
    freq_hz: np.ndarray = field(default_factory=lambda: np.zeros(0))
    stable: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))
    stability: np.ndarray | None = None  # int8: 1 stable, 0 unstable, -1 unknown, 2/3 carried
    stability_how: np.ndarray | None = None  # int8: 0 none, 1 Hill, 2 linear, 3 carried
    newton_its: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    energy_residual: np.ndarray = field(default_factory=lambda: np.zeros(0))
    out_amp: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    out_h1: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    out_rms: np.ndarray | None = None  # (n_points, n_out) RMS over the period
    out_harm: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 0)))
    status: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), np.int8))
    friction_energy: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    x: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    work_ext: np.ndarray = field(default_factory=lambda: np.zeros(0))
    work_visc: np.ndarray = field(default_factory=lambda: np.zeros(0))
    work_friction: np.ndarray = field(default_factory=lambda: np.zeros(0))
    work_normal: np.ndarray = field(default_factory=lambda: np.zeros(0))
    max_floquet_real: np.ndarray = field(default_factory=lambda: np.zeros(0))
    accuracy: np.ndarray | None = None  # loop-energy vs harmonic-work mismatch (-)
    completed: bool = False
    failed: bool = False
    message: str = ""
    timings: dict[str, float] = field(default_factory=dict)
    stats: dict[str, Any] = field(default_factory=dict)
    options: dict[str, Any] = field(default_factory=dict)
    label: str = ""

    LAYOUT: ClassVar[Layout] = LAYOUT

    def __post_init__(self) -> None:
        self.stable = np.asarray(self.stable, dtype=bool)
        if self.stability is None or np.size(self.stability) != self.stable.size:
            # a record without verdicts (older files): stable or unstable as stored
            self.stability = self.stable.astype(np.int8)
        self.stability = np.asarray(self.stability, dtype=np.int8)
        if self.stability_how is None or np.size(self.stability_how) != self.stable.size:
            # older files: Hill's method ran at every point where a verdict is stored
            self.stability_how = np.where(self.stability >= 0, 1, 0)
        self.stability_how = np.asarray(self.stability_how, dtype=np.int8)
        if self.out_rms is None or np.shape(self.out_rms) != np.shape(self.out_amp):
            # older files: from the stored output harmonics (Q0^2 + sum (Qc^2 + Qs^2) / 2)
            w = np.concatenate([[1.0] if h == 0 else [0.5, 0.5] for h in self.harmonics])
            oh = np.asarray(self.out_harm, dtype=float)
            self.out_rms = (
                np.sqrt(np.einsum("h,ihj->ij", w, oh**2))
                if oh.ndim == 3 and oh.shape[1] == w.size
                else np.zeros_like(np.asarray(self.out_amp, dtype=float))
            )
        if self.accuracy is None or np.size(self.accuracy) != self.stable.size:
            self.accuracy = np.full(self.stable.size, np.nan)  # not computed (older files)
        self.accuracy = np.asarray(self.accuracy, dtype=float)

    @property
    def unstable(self) -> np.ndarray:
        """(n_points,) bool: Hill found an exponent with a positive real part at the point."""
        return self.stability == 0

    @property
    def unknown(self) -> np.ndarray:
        """(n_points,) bool: stability not determined (off, solver failure, count check)."""
        return self.stability < 0

    @property
    def carried(self) -> np.ndarray:
        """(n_points,) bool: the verdict of the checked neighbours, not computed at the point."""
        return self.stability >= 2

    def stability_name(self, i: int) -> str:
        """ "stable", "unstable", "unknown", "stable (carried)" or "unstable (carried)"."""
        from ..stability.hill import VERDICT_NAMES

        return VERDICT_NAMES.get(int(self.stability[i]), "unknown")

    @property
    def n_points(self) -> int:
        return int(self.freq_hz.size)

    def peak(self, output: int = 0) -> int:
        """Index of the point with the largest output amplitude (-1 if empty)."""
        if self.n_points == 0:
            return -1
        return int(np.argmax(self.out_amp[:, output]))

    def _argmax(self, values: np.ndarray, output: int) -> int:
        return int(np.argmax(values[:, output])) if self.n_points else -1

    def peak_inside(self, i: int) -> bool:
        """True if point ``i`` is a maximum inside the band, not a band end (a peak reached)."""
        return 0 < i < self.n_points - 1

    def summary(self, output: int = 0) -> dict[str, Any]:
        """The numbers the CLI prints for this curve (amplitudes in the model's length unit).

        Three peaks, each at its own frequency: ``peak_*`` the largest
        ``|y(t)|`` over the period, ``h1_*`` the largest harmonic-1 amplitude,
        ``rms_*`` the largest RMS over the period; ``peak_reached`` (and
        ``h1_peak_reached``) is False when that maximum lies at a band end (the
        curve is still rising there: not a resonance peak).
        """
        i = self.peak(output)
        j = self._argmax(self.out_h1, output)
        k = self._argmax(self.out_rms, output)

        def at(arr, n):
            return float(arr[n]) if n >= 0 else None

        return dict(
            level=self.level,
            peak_frequency_hz=at(self.freq_hz, i),
            peak_amplitude=float(self.out_amp[i, output]) if i >= 0 else None,
            peak_reached=self.peak_inside(i) if i >= 0 else None,
            h1_peak_frequency_hz=at(self.freq_hz, j),
            h1_amplitude=float(self.out_h1[j, output]) if j >= 0 else None,
            h1_peak_reached=self.peak_inside(j) if j >= 0 else None,
            rms_peak_frequency_hz=at(self.freq_hz, k),
            rms_amplitude=float(self.out_rms[k, output]) if k >= 0 else None,
            peak_stable=bool(self.stable[i]) if i >= 0 else None,
            peak_stability=self.stability_name(i) if i >= 0 else None,
            n_points=self.n_points,
            n_unstable=int(np.sum(self.unstable)),
            n_stability_unknown=int(np.sum(self.unknown)),
            n_stable_carried=int(np.sum(self.stability == 2)),
            n_unstable_carried=int(np.sum(self.stability == 3)),
            n_hill_checks=int(np.sum(self.stability_how == 1)),
            wall_s=round(float(self.timings.get("total", 0.0)), 4),
            energy_residual_max=float(np.max(self.energy_residual)) if self.n_points else None,
            accuracy_max=_nanmax(self.accuracy),
            accuracy_warning=self.stats.get("accuracy_warning") or None,
            newton_its=int(np.sum(self.newton_its)),
            completed=self.completed,
            failed=self.failed,
            message=self.message,
        )

    @classmethod
    def from_file(cls, kw: dict[str, Any]) -> dict[str, Any]:
        kw["stable"] = kw["stable"].astype(bool)
        return kw

    def to_csv(self, path: str | Path, unit_scale: float = 1.0, unit: str = "m") -> Path:
        """One row per point: frequency, stability, per-output amplitudes, energies."""
        from ...io import write_text

        cols = ["freq_hz", "stable", "stability", "stability_how", "newton_its"]
        cols += ["energy_residual", "accuracy"]
        for nm in self.output_names:
            cols += [f"{nm}_amp_{unit}", f"{nm}_h1_{unit}", f"{nm}_rms_{unit}"]
        cols += [
            "friction_energy_j",
            "viscous_energy_j",
            "excitation_work_j",
            "n_stuck",
            "n_stick_slip",
            "n_partial_separation",
            "n_full_separation",
        ]
        lines = [",".join(cols)]
        for i in range(self.n_points):
            row = [
                f"{self.freq_hz[i]:.9g}",
                str(int(self.stable[i])),
                self.stability_name(i),
                ("none", "hill", "linear", "carried")[int(self.stability_how[i])],
                str(int(self.newton_its[i])),
                f"{self.energy_residual[i]:.3e}",
                f"{self.accuracy[i]:.3e}",
            ]
            for j in range(len(self.output_names)):
                row += [
                    f"{self.out_amp[i, j] * unit_scale:.9g}",
                    f"{self.out_h1[i, j] * unit_scale:.9g}",
                    f"{self.out_rms[i, j] * unit_scale:.9g}",
                ]
            counts = (
                np.bincount(self.status[i].astype(int), minlength=4)
                if self.status.shape[1]
                else [0] * 4
            )
            row += [
                f"{self.work_friction[i]:.9g}",
                f"{self.work_visc[i]:.9g}",
                f"{self.work_ext[i]:.9g}",
            ]
            row += [str(int(c)) for c in counts[:4]]
            lines.append(",".join(row))
        return write_text(path, "\n".join(lines) + "\n")


def _nanmax(a: np.ndarray) -> float | None:
    a = np.asarray(a, dtype=float)
    return float(np.nanmax(a)) if a.size and np.isfinite(a).any() else None


def arc_length(
    freq: np.ndarray, amp: np.ndarray, box: tuple[float, float, float, float]
) -> np.ndarray:
    """Cumulative arc length of a curve in the box-normalised (frequency, amplitude) plane."""
    f0, f1, a0, a1 = box
    p = np.column_stack(
        [
            (np.asarray(freq) - f0) / max(f1 - f0, 1e-300),
            (np.asarray(amp) - a0) / max(a1 - a0, 1e-300),
        ]
    )
    return np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(p, axis=0).T))])


def curve_distance(
    freq_a: np.ndarray, amp_a: np.ndarray, freq_b: np.ndarray, amp_b: np.ndarray
) -> float:
    """Largest distance between two curves, point to nearest point of the other polyline.

    Both curves are normalised to the box of their union (frequency and
    amplitude each mapped to [0, 1]), so the result is a fraction of the
    plot; it is symmetric (a Hausdorff distance) and independent of how the
    points are spaced along either curve.
    """
    fa, aa, fb, ab = (np.asarray(v, dtype=float) for v in (freq_a, amp_a, freq_b, amp_b))
    f0, f1 = min(fa.min(), fb.min()), max(fa.max(), fb.max())
    a0, a1 = min(aa.min(), ab.min()), max(aa.max(), ab.max())
    sf, sa = max(f1 - f0, 1e-300), max(a1 - a0, 1e-300)
    A = np.column_stack([(fa - f0) / sf, (aa - a0) / sa])
    B = np.column_stack([(fb - f0) / sf, (ab - a0) / sa])
    return max(_to_polyline(A, B).max(), _to_polyline(B, A).max())


def _to_polyline(P: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """Distance of each point of P to the polyline through Q."""
    if Q.shape[0] == 1:
        return np.hypot(*(P - Q[0]).T)
    a = Q[:-1][None]  # (1, m, 2)
    d = (Q[1:] - Q[:-1])[None]
    p = P[:, None]
    L2 = np.maximum((d**2).sum(-1), 1e-300)
    t = np.clip(((p - a) * d).sum(-1) / L2, 0.0, 1.0)
    proj = a + t[..., None] * d
    return np.sqrt(((p - proj) ** 2).sum(-1)).min(axis=1)

"""The backbone record of a nonlinear mode: :class:`NlModeBranch` (arrays per point).

Written by :func:`workbench.hbm.nlmodes.backbone.nonlinear_mode`, read by
:mod:`.synthesis` (the forced response rebuilt from the backbone), the
studies and the figures; saved to HDF5 and CSV.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from ...io.record import Layout, PathRecord
from ..core.fourier import Fourier

POINT_ARRAYS = (
    "amplitude",
    "freq_hz",
    "xi",
    "xi_viscous",
    "damping_ratio",
    "friction_energy",
    "status",
    "energy_residual",
    "work_friction",
    "work_viscous",
    "mac",
    "higher_harmonics",
    "out_amp",
    "out_h1",
    "newton_its",
    "psi",
)


LAYOUT = Layout(
    datasets=(*POINT_ARRAYS, "linear_hz", "lin_phi", "lin_c", "obs"),
    required=(*POINT_ARRAYS, "linear_hz"),
    attrs=(
        ("mode", "int"),
        ("f_stuck_hz", "float"),
        ("nt", "int"),
        ("n", "int"),
        ("completed", "bool"),
        ("failed", "bool"),
        ("message", "str"),
        ("label", "str"),
        ("harmonics", "ints"),
        ("output_names", "names"),
        ("timings", "json"),
    ),
)


@dataclass
class NlModeBranch(PathRecord):
    """A backbone: one nonlinear mode against its modal amplitude (arrays per point).

    ``amplitude`` (sqrt(kg) m: the harmonic-1 motion is ``a psi_1`` with
    ``psi_1^H M psi_1 = 1``), ``freq_hz``, ``xi`` (1/s), ``damping_ratio``
    (``xi / 2 omega``), ``xi_viscous`` (1/s: ``psi_1^H C psi_1``, the viscous
    share of ``xi``), ``friction_energy`` (n_el, J per cycle), ``status``
    (n_el: 0 stuck, 1 stick-slip, 2 partial, 3 full separation),
    ``energy_residual`` (relative: energy fed by ``xi`` against viscous +
    contact work), ``work_friction`` / ``work_viscous`` (J per cycle),
    ``mac`` (of the harmonic-1 shape against the first point, mass
    weighted), ``higher_harmonics`` (share of the kinetic-energy norm in
    harmonics other than 1), ``out_amp`` / ``out_h1`` (n_out: the largest
    ``|y(t)|`` and the harmonic-1 amplitude of each output, model length
    unit), ``newton_its``, ``psi`` (nh * n: the harmonics per unit modal
    amplitude, layout of :mod:`..core.fourier`).
    """

    mode: int
    f_stuck_hz: float
    linear_hz: np.ndarray  # every linear (stuck) frequency of the model, Hz
    harmonics: tuple[int, ...]
    nt: int
    n: int
    output_names: tuple[str, ...]
    amplitude: np.ndarray = field(default_factory=lambda: np.zeros(0))
    freq_hz: np.ndarray = field(default_factory=lambda: np.zeros(0))
    xi: np.ndarray = field(default_factory=lambda: np.zeros(0))
    xi_viscous: np.ndarray = field(default_factory=lambda: np.zeros(0))
    damping_ratio: np.ndarray = field(default_factory=lambda: np.zeros(0))
    friction_energy: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    status: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), np.int8))
    energy_residual: np.ndarray = field(default_factory=lambda: np.zeros(0))
    work_friction: np.ndarray = field(default_factory=lambda: np.zeros(0))
    work_viscous: np.ndarray = field(default_factory=lambda: np.zeros(0))
    mac: np.ndarray = field(default_factory=lambda: np.zeros(0))
    higher_harmonics: np.ndarray = field(default_factory=lambda: np.zeros(0))
    out_amp: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    out_h1: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    newton_its: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    psi: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    completed: bool = False
    failed: bool = False
    message: str = ""
    timings: dict[str, float] = field(default_factory=dict)
    label: str = ""
    # the linear (stuck) modes, for the other modes' share of a synthesised response
    lin_phi: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # (n, n_m)
    lin_c: np.ndarray = field(default_factory=lambda: np.zeros(0))  # (n_m,) 2 zeta w, 1/s
    obs: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # (n_out, n)

    LAYOUT: ClassVar[Layout] = LAYOUT

    @property
    def n_points(self) -> int:
        return int(self.amplitude.size)

    def other_modes_response(self, f1: np.ndarray, freq_hz: float) -> np.ndarray:
        """(n_out,) complex: the stuck linear response of every mode but the followed one to
        ``f1`` at ``freq_hz`` (what a single-mode synthesis leaves out), m per unit level."""
        if not self.lin_phi.size:
            return np.zeros(self.obs.shape[0] if self.obs.size else 1, complex)
        W = 2 * np.pi * freq_hz
        wn = 2 * np.pi * self.linear_hz
        d = 1.0 / (wn**2 - W**2 + 1j * W * self.lin_c)
        d[self.mode] = 0.0
        return (self.obs @ self.lin_phi) @ (d * (self.lin_phi.T @ np.asarray(f1, complex)))

    @property
    def fourier(self) -> Fourier:
        return Fourier(self.harmonics, self.nt)

    def psi_of(self, i: int) -> np.ndarray:
        """(nh, n) harmonics per unit modal amplitude at point ``i``."""
        return self.psi[i].reshape(len(self.fourier.k), self.n)

    def psi1(self) -> np.ndarray:
        """(n_points, n) complex harmonic-1 shapes ``psi_c1 - i psi_s1``."""
        f = self.fourier
        c = f.index(1, "c")
        P = self.psi.reshape(self.n_points, f.nh, self.n)
        return P[:, c] - 1j * P[:, c + 1]

    def summary(self) -> dict[str, Any]:
        """The numbers the CLI prints for this backbone."""
        if not self.n_points:
            return dict(
                mode=self.mode,
                n_points=0,
                completed=self.completed,
                failed=self.failed,
                message=self.message,
            )
        i = int(np.argmax(self.damping_ratio))
        return dict(
            mode=self.mode,
            f_stuck_hz=self.f_stuck_hz,
            freq_first_hz=float(self.freq_hz[0]),
            freq_last_hz=float(self.freq_hz[-1]),
            damping_first=float(self.damping_ratio[0]),
            damping_max=float(self.damping_ratio[i]),
            amplitude_at_damping_max=float(self.amplitude[i]),
            freq_at_damping_max_hz=float(self.freq_hz[i]),
            amplitude_range=[float(self.amplitude[0]), float(self.amplitude[-1])],
            mac_min=float(self.mac.min()),
            energy_residual_max=float(self.energy_residual.max()),
            n_points=self.n_points,
            newton_its=int(self.newton_its.sum()),
            wall_s=round(float(self.timings.get("total", 0.0)), 4),
            completed=self.completed,
            failed=self.failed,
            message=self.message,
        )

    def to_csv(self, path: str | Path, unit: str = "m") -> Path:
        """One row per point: amplitude, frequency, damping, energy, status counts, outputs."""
        from ...io.csv_rows import write_rows_csv

        rows = []
        for i in range(self.n_points):
            st = self.status[i] if self.status.size else np.zeros(0, int)
            row = {
                "modal_amplitude": float(self.amplitude[i]),
                "freq_hz": float(self.freq_hz[i]),
                "damping_ratio": float(self.damping_ratio[i]),
                "xi_per_s": float(self.xi[i]),
                "friction_energy_j": float(self.friction_energy[i].sum()),
                "n_stuck": int(np.sum(st == 0)),
                "n_stick_slip": int(np.sum(st == 1)),
                "n_partial_sep": int(np.sum(st == 2)),
                "n_separated": int(np.sum(st == 3)),
                "mac": float(self.mac[i]),
                "higher_harmonics": float(self.higher_harmonics[i]),
                "energy_residual": float(self.energy_residual[i]),
            }
            for j, nm in enumerate(self.output_names):
                row[f"{nm}_amp_{unit}"] = float(self.out_amp[i, j])
            rows.append(row)
        return write_rows_csv(path, rows)

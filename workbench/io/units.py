"""Unit attributes of the HDF5 files the workbench writes (docs/RESULTS.md lists them).

Every numeric dataset gets an attribute ``unit`` (a UCUM-like string: ``Hz``,
``m``, ``J``, ``kg``, ``N/m``, ``1`` for a pure number) and, where the
number needs a word, ``description``. Readers never depend on them; they
are there for a person (or h5dump, HDFView, h5py) opening the file.
"""

from __future__ import annotations

from typing import Any

# Branch datasets (workbench.hbm.forced.branch); "L" is the model's length unit
BRANCH_UNITS: dict[str, tuple[str, str]] = {
    "freq_hz": ("Hz", "excitation frequency of each point, in continuation order"),
    "stable": ("1", "True only for an established stable verdict (Hill or linear)"),
    "stability": (
        "1",
        "Hill stability of each point: 1 stable, 0 unstable, -1 unknown, 2/3 stable/unstable "
        "carried from checked neighbours",
    ),
    "stability_how": (
        "1",
        "how the verdict was obtained: 0 not computed, 1 Hill at the point, 2 every contact "
        "stuck (linear), 3 carried",
    ),
    "accuracy": ("1", "loop energy against harmonic contact work, over the excitation work"),
    "out_rms": ("L", "RMS of y(t) over the period, per output"),
    "newton_its": ("1", "Newton iterations of the corrector"),
    "energy_residual": ("1", "relative energy balance residual per cycle"),
    "out_amp": ("L", "largest |y(t)| over the period, per output"),
    "out_h1": ("L", "harmonic-1 amplitude per output"),
    "out_harm": ("L", "output harmonics (nh, n_out), Fourier layout of hbm/core/fourier.py"),
    "status": (
        "1",
        "contact status per pair: 0 stuck, 1 stick-slip, 2 partial separation, 3 full separation",
    ),
    "friction_energy": ("J", "friction energy dissipated per cycle, per pair"),
    "x": ("L", "solved harmonic unknowns (layout of hbm/core/balance.py)"),
    "work_ext": ("J", "work of the excitation per cycle"),
    "work_visc": ("J", "viscous dissipation per cycle"),
    "work_friction": ("J", "tangential contact work per cycle"),
    "work_normal": ("J", "normal contact work per cycle (quadrature error where it opens)"),
    "max_floquet_real": ("1/s", "largest real part of the Floquet exponents"),
}

CASE_UNITS: dict[str, tuple[str, str]] = {
    "case/points": ("m", "contact pair coordinates (n_pairs, 3)"),
    "case/side": ("1", "side of the groove of each pair (0 or 1)"),
}

REDUCED_UNITS: dict[str, tuple[str, str]] = {
    "K": ("N/m", "reduced stiffness (N m/rad for rotations of a rigid damper)"),
    "M": ("kg", "reduced mass (kg m^2 for rotations of a rigid damper)"),
    "T": ("1", "interface node displacements (m) from the generalised coordinates"),
    "node_coords": ("m", "interface node coordinates (n_nodes, 3)"),
    "mode_freqs_hz": ("Hz", "fixed-interface mode frequencies"),
    "ref_point": ("m", "reference point of a rigid body"),
}


def annotate(
    h5: Any, units: dict[str, tuple[str, str]], length_unit: str = "m", prefix: str = ""
) -> None:
    """Set ``unit`` and ``description`` on every listed dataset present in ``h5``."""
    for name, (unit, text) in units.items():
        key = f"{prefix}{name}"
        if key in h5:
            h5[key].attrs["unit"] = length_unit if unit == "L" else unit
            h5[key].attrs["description"] = text

"""The study options table and the named robustness methods and hard cases (plain data).

Every option of ``upd study`` is one :class:`Option` in :data:`OPTIONS`
(name, type, default, help, allowed values, and the physical range of a
real rig with its reason); :mod:`workbench.studies.spec`
turns them into a :class:`~workbench.studies.spec.StudySpec` from a TOML
file and the command line, and the figures read an option's help text for
their axis labels. The robustness study's solution methods
(:data:`METHODS`) and hard cases (:data:`CASES`) are named in
:mod:`workbench.hard_cases` and listed here by the options that name them.
Nothing here computes: it imports no study.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from .geometry.params import DAMPERS
from .hard_cases import CASES, METHODS
from .limits import (
    BAND_MAX_HZ,
    BAND_WHY,
    CF_MAX_N,
    CF_WHY,
    FORCE_MAX_N,
    FORCE_WHY,
    K_FACE_N_PER_M3,
    K_FACE_WHY,
    K_LINE_N_PER_M2,
    K_LINE_WHY,
    UQ_THRESHOLD_MAX_MM,
    UQ_THRESHOLD_WHY,
)

# the robustness study's names, for the options that list them
ROBUSTNESS_METHODS = tuple(METHODS)
ROBUSTNESS_CASES = tuple(CASES)
__all__ = [
    "BY_NAME",
    "KINDS",
    "OPTIONS",
    "Option",
]


KINDS = ("comparison", "sweep", "fidelity", "robustness", "uncertainty")


@dataclass(frozen=True)
class Option:
    """One study option: its name, type, default, help and allowed values."""

    name: str  # dashed, e.g. "mesh-size"
    kind: str  # "float", "int", "bool", "str", "floats", "ints", "strs", "path"
    default: Any
    help: str
    group: str
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    choices: tuple[str, ...] | None = None
    optional: bool = False  # None allowed ("use the geometry/contact file's value")
    unit: str = ""
    # the range a real rig cannot leave (allow-extreme passes it) and its reason
    soft_lo: float | None = None
    soft_hi: float | None = None
    why: str = ""
    power_of_2: bool = False  # an int that must be a power of 2

    @property
    def attr(self) -> str:
        return self.name.replace("-", "_")


OPTIONS: tuple[Option, ...] = (
    # what to compute
    Option("name", "str", "study", "a name for the study (report title, file names)", "study"),
    Option(
        "allow-extreme",
        "bool",
        False,
        "accept values beyond the physical ranges of a real rig (forces, cf, contact "
        "stiffness, bands, uq-threshold) for a numerical experiment; the numerical limits stay",
        "study",
    ),
    Option(
        "kind",
        "str",
        "comparison",
        "what the report shows: " + ", ".join(KINDS),
        "study",
        choices=KINDS,
    ),
    Option("dampers", "strs", list(DAMPERS), "dampers to compare", "cases", choices=DAMPERS),
    Option(
        "phases",
        "floats",
        [0.0, 180.0],
        "inter-blade phase angles, deg (0 in-phase, 180 out-of-phase)",
        "cases",
        lo=-360.0,
        hi=360.0,
    ),
    Option(
        "forces",
        "floats",
        [0.096, 3.84, 9.6, 15.0, 20.0, 25.0, 30.0],
        "excitation force amplitudes on each blade, N",
        "cases",
        lo=0.0,
        lo_open=True,
        unit="N",
        soft_hi=FORCE_MAX_N,
        why=FORCE_WHY,
    ),
    Option(
        "response-blade", "int", 1, "blade whose response is reported (1 or 2)", "cases", lo=1, hi=2
    ),
    # frequency band
    Option(
        "band-in-phase",
        "floats",
        [],
        "band of the in-phase family [lo, hi], Hz "
        "(empty: automatic from the linear stuck and sliding limits)",
        "band",
        lo=0.0,
        lo_open=True,
        unit="Hz",
        soft_hi=BAND_MAX_HZ,
        why=BAND_WHY,
    ),
    Option(
        "band-out-of-phase",
        "floats",
        [],
        "band of the out-of-phase family [lo, hi], Hz (empty: automatic)",
        "band",
        lo=0.0,
        lo_open=True,
        unit="Hz",
        soft_hi=BAND_MAX_HZ,
        why=BAND_WHY,
    ),
    Option(
        "band-margin",
        "float",
        0.04,
        "automatic band: relative margin beyond the linear limits",
        "band",
        lo=0.0,
        lo_open=True,
        hi=0.5,
    ),
    # contact and loads (None: geometry/contact.toml)
    Option("mu", "float", None, "friction coefficient", "contact", lo=0.0, hi=2.0, optional=True),
    Option(
        "cf",
        "float",
        None,
        "centrifugal force on the damper, N",
        "contact",
        lo=0.0,
        lo_open=True,
        optional=True,
        unit="N",
        soft_hi=CF_MAX_N,
        why=CF_WHY,
    ),
    Option(
        "kt-line",
        "float",
        None,
        "tangential stiffness per metre of line (cone, cylinder), N/m per m",
        "contact",
        lo=0.0,
        lo_open=True,
        optional=True,
        unit="N/m per m",
        soft_lo=K_LINE_N_PER_M2[0],
        soft_hi=K_LINE_N_PER_M2[1],
        why=K_LINE_WHY,
    ),
    Option(
        "kn-line",
        "float",
        None,
        "normal stiffness per metre of line, N/m per m",
        "contact",
        lo=0.0,
        lo_open=True,
        optional=True,
        unit="N/m per m",
        soft_lo=K_LINE_N_PER_M2[0],
        soft_hi=K_LINE_N_PER_M2[1],
        why=K_LINE_WHY,
    ),
    Option(
        "kt-face",
        "float",
        None,
        "tangential stiffness per m^2 of face (wedge), N/m per m^2",
        "contact",
        lo=0.0,
        lo_open=True,
        optional=True,
        unit="N/m per m^2",
        soft_lo=K_FACE_N_PER_M3[0],
        soft_hi=K_FACE_N_PER_M3[1],
        why=K_FACE_WHY,
    ),
    Option(
        "kn-face",
        "float",
        None,
        "normal stiffness per m^2 of face (wedge), N/m per m^2",
        "contact",
        lo=0.0,
        lo_open=True,
        optional=True,
        unit="N/m per m^2",
        soft_lo=K_FACE_N_PER_M3[0],
        soft_hi=K_FACE_N_PER_M3[1],
        why=K_FACE_WHY,
    ),
    Option(
        "damping",
        "float",
        0.002,
        "modal damping ratio of the assembly (stuck contacts)",
        "contact",
        lo=0.0,
        hi=0.5,
    ),
    # modelling knobs (fidelity)
    Option(
        "mesh-size",
        "float",
        None,
        "global mesh size, mm (None: the geometry file's)",
        "fidelity",
        lo=0.0,
        lo_open=True,
        hi=1000.0,
        optional=True,
        unit="mm",
    ),
    Option(
        "modes",
        "int",
        12,
        "fixed-interface modes per body (Craig-Bampton)",
        "fidelity",
        lo=0,
        hi=400,
    ),
    Option(
        "rigid-damper", "bool", False, "rigid 6-DOF damper instead of Craig-Bampton", "fidelity"
    ),
    Option(
        "points-per-line",
        "int",
        None,
        "contact points per line (cone, cylinder)",
        "fidelity",
        lo=2,
        hi=400,
        optional=True,
    ),
    Option("harmonics", "ints", [0, 1, 2, 3], "harmonics of the balance", "fidelity", lo=0, hi=64),
    Option(
        "nt",
        "int",
        None,
        "AFT time samples per period (None: solver default)",
        "fidelity",
        lo=4,
        hi=8192,
        optional=True,
    ),
    # geometry
    Option(
        "geometry",
        "path",
        None,
        "TOML overriding geometry tables (rig, cone, ...)",
        "geometry",
        optional=True,
    ),
    Option(
        "cone-angle",
        "float",
        None,
        "cone semi-angle, deg (None: cone.toml's)",
        "geometry",
        lo=0.0,
        lo_open=True,
        hi=89.0,
        optional=True,
    ),
    # solver
    Option(
        "max-points",
        "int",
        400,
        "largest number of continuation points per curve",
        "solver",
        lo=5,
        hi=100000,
    ),
    Option("stability", "bool", True, "Hill stability of every point", "solver"),
    Option(
        "nonlinear-modes",
        "bool",
        False,
        "comparison study: also one nonlinear mode "
        "(backbone) per damper and family, the forced responses synthesised from it and "
        "their check against the curves (workbench/studies/nlmodes.py)",
        "solver",
    ),
    Option(
        "field-shapes",
        "bool",
        False,
        "also write cases/<case>_peak_field.vtu: the displacement at each curve's peak on "
        "the full rig and damper meshes (ParaView; about one reduction's eigen solve per "
        "damper, workbench/studies/fields.py)",
        "solver",
    ),
    # sweeps and the fidelity/robustness studies
    Option(
        "sweep",
        "str",
        None,
        "name of a scalar option to sweep (e.g. cf, cone-angle, mu)",
        "sweep",
        optional=True,
    ),
    Option("sweep-values", "floats", [], "values of the swept option", "sweep"),
    Option(
        "tolerance",
        "percent",
        None,
        "accepted error, percent ('1' or '1%%'): pick the "
        "cheapest settings meeting it (fidelity studies)",
        "fidelity",
        lo=0.0,
        lo_open=True,
        hi=100.0,
        optional=True,
    ),
    # ---- fidelity study options (kind = "fidelity"; workbench/studies/fidelity.py) ----
    Option(
        "knobs",
        "strs",
        ["mesh-size", "modes", "harmonics", "nt", "points-per-line", "rigid-damper"],
        "knobs a fidelity study varies, one at a time about the base setting (the study's "
        "own mesh-size, modes, ...)",
        "fidelity",
        choices=("mesh-size", "modes", "harmonics", "nt", "points-per-line", "rigid-damper"),
    ),
    Option(
        "levels-mesh-size",
        "floats",
        [14.0, 11.0, 9.0, 7.0],
        "fidelity: global mesh sizes to try, mm (finest = smallest)",
        "fidelity",
        lo=0.0,
        lo_open=True,
    ),
    Option(
        "levels-modes",
        "ints",
        [4, 8, 12, 24, 40],
        "fidelity: fixed-interface modes per body to try",
        "fidelity",
        lo=0,
        hi=400,
    ),
    Option(
        "levels-harmonics",
        "strs",
        ["1", "0-1", "0-3", "0-5", "0-7"],
        "fidelity: harmonic sets to try, each 'a-b' (a range) or 'h+h+...' (a list)",
        "fidelity",
    ),
    Option(
        "levels-nt",
        "ints",
        [16, 32, 64, 128, 256, 512],
        "fidelity: AFT time samples per period to try",
        "fidelity",
        lo=4,
        hi=8192,
    ),
    Option(
        "levels-points-per-line",
        "ints",
        [5, 11, 23, 33, 45],
        "fidelity: contact points per line to try",
        "fidelity",
        lo=2,
        hi=400,
    ),
    Option(
        "levels-rigid-damper",
        "strs",
        ["rigid", "flexible"],
        "fidelity: damper models to try (finest = flexible)",
        "fidelity",
        choices=("rigid", "flexible"),
    ),
    # ---- robustness study options (kind = "robustness"; workbench/studies/robustness.py) ----
    Option(
        "methods",
        "strs",
        list(ROBUSTNESS_METHODS),
        "solution methods of a robustness "
        "study (named solver variants; the first is the reference): "
        + ", ".join(ROBUSTNESS_METHODS),
        "robustness",
        choices=ROBUSTNESS_METHODS,
    ),
    Option(
        "hard-cases",
        "strs",
        list(ROBUSTNESS_CASES),
        "hard cases of a robustness study: " + ", ".join(ROBUSTNESS_CASES),
        "robustness",
        choices=ROBUSTNESS_CASES,
    ),
    Option(
        "peak-tolerance",
        "float",
        1.0,
        "robustness: a method that converges but whose "
        "peak amplitude differs from the first method's by more than this, percent, is a "
        "wrong answer",
        "robustness",
        lo=0.0,
        lo_open=True,
        hi=100.0,
    ),
    Option(
        "time-check",
        "bool",
        True,
        "robustness: check the harmonic balance against time "
        "integration at its suspect points (small models)",
        "robustness",
    ),
    # ---- uncertainty study options (kind = "uncertainty"; workbench/studies/uncertainty.py) --
    # a distribution is "uniform LO HI", "normal MEAN SD [LO HI]" or
    # "lognormal MEDIAN SIGMA_LN [LO HI]" (bounds truncate); cf, kt, kn are factors on the
    # nominal value (study option or geometry/contact.toml), mu and damping absolute values,
    # seat-tilt the misalignment of one side's seat, deg
    Option(
        "uq-inputs",
        "strs",
        ["mu", "cf", "kt", "kn", "damping", "seat-tilt"],
        "uncertainty: the inputs that vary (the others stay nominal)",
        "uncertainty",
        choices=("mu", "cf", "kt", "kn", "damping", "seat-tilt"),
    ),
    Option(
        "uq-mu",
        "str",
        "normal 0.5 0.1 0.25 0.75",
        "uncertainty: friction coefficient",
        "uncertainty",
    ),
    Option(
        "uq-cf",
        "str",
        "normal 1 0.1 0.7 1.3",
        "uncertainty: factor on the nominal centrifugal force",
        "uncertainty",
    ),
    Option(
        "uq-kt",
        "str",
        "lognormal 1 0.5 0.25 4",
        "uncertainty: factor on the nominal tangential contact stiffness (line and face)",
        "uncertainty",
    ),
    Option(
        "uq-kn",
        "str",
        "lognormal 1 0.5 0.25 4",
        "uncertainty: factor on the nominal normal contact stiffness (line and face)",
        "uncertainty",
    ),
    Option(
        "uq-damping",
        "str",
        "lognormal 0.002 0.3 0.001 0.004",
        "uncertainty: modal damping ratio",
        "uncertainty",
    ),
    Option(
        "uq-seat-tilt",
        "str",
        "normal 0 0.01 -0.03 0.03",
        "uncertainty: seat "
        "misalignment of one side, deg (tilts the preload along the line or face; "
        "opens one end when large)",
        "uncertainty",
    ),
    Option(
        "uq-samples",
        "int",
        16,
        "uncertainty: base samples N per damper and family "
        "(Saltelli design: N (D + 2) cases; a power of 2; a larger N reuses a smaller)",
        "uncertainty",
        lo=2,
        hi=1 << 20,
        power_of_2=True,
    ),
    Option(
        "uq-seed",
        "int",
        2026,
        "uncertainty: seed of the scrambled Sobol sequence",
        "uncertainty",
        lo=0,
        hi=2**31 - 1,
    ),
    Option(
        "uq-threshold",
        "float",
        None,
        "uncertainty: peak amplitude threshold, mm (the "
        "report gives the probability of exceeding it; None: per family, 1.2 x the "
        "median peak of every damper's samples)",
        "uncertainty",
        lo=0.0,
        lo_open=True,
        optional=True,
        unit="mm",
        soft_hi=UQ_THRESHOLD_MAX_MM,
        why=UQ_THRESHOLD_WHY,
    ),
    Option(
        "uq-schedule",
        "str",
        "dynamic",
        "uncertainty: how samples spread over MPI ranks: "
        "dynamic (a shared counter, each rank takes the next sample when free) or static "
        "(round-robin, for comparison)",
        "uncertainty",
        choices=("dynamic", "static"),
    ),
)


BY_NAME = {o.name: o for o in OPTIONS}

"""The uncertainty study's own options: the uncertain inputs, their distributions, the design.

Declared once here; ``upd study`` (parser and help), the study specification,
the report's input table and docs/STUDIES.md read them through the kind
registry (:mod:`workbench.studies.kinds`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ....errors import InputError
from ....limits import UQ_THRESHOLD_MAX_MM, UQ_THRESHOLD_WHY
from ....study_options import option


@dataclass(frozen=True)
class UncertaintyOptions:
    """The uncertainty study's own options, one field each (``spec.uncertainty.<name>``)."""

    # a distribution is "uniform LO HI", "normal MEAN SD [LO HI]" or
    # "lognormal MEDIAN SIGMA_LN [LO HI]" (bounds truncate); cf, kt, kn are factors on the
    # nominal value (study option or geometry/contact.toml), mu and damping absolute values,
    # seat-tilt the misalignment of one side's seat, deg
    uq_inputs: list[str] = option(
        "strs",
        ["mu", "cf", "kt", "kn", "damping", "seat-tilt"],
        "uncertainty: the inputs that vary (the others stay nominal)",
        "uncertainty",
        choices=("mu", "cf", "kt", "kn", "damping", "seat-tilt"),
    )
    uq_mu: str = option(
        "str", "normal 0.5 0.1 0.25 0.75", "uncertainty: friction coefficient", "uncertainty"
    )
    uq_cf: str = option(
        "str",
        "normal 1 0.1 0.7 1.3",
        "uncertainty: factor on the nominal centrifugal force",
        "uncertainty",
    )
    uq_kt: str = option(
        "str",
        "lognormal 1 0.5 0.25 4",
        "uncertainty: factor on the nominal tangential contact stiffness (line and face)",
        "uncertainty",
    )
    uq_kn: str = option(
        "str",
        "lognormal 1 0.5 0.25 4",
        "uncertainty: factor on the nominal normal contact stiffness (line and face)",
        "uncertainty",
    )
    uq_damping: str = option(
        "str", "lognormal 0.002 0.3 0.001 0.004", "uncertainty: modal damping ratio", "uncertainty"
    )
    uq_seat_tilt: str = option(
        "str",
        "normal 0 0.01 -0.03 0.03",
        "uncertainty: seat "
        "misalignment of one side, deg (tilts the preload along the line or face; "
        "opens one end when large)",
        "uncertainty",
    )
    uq_samples: int = option(
        "int",
        16,
        "uncertainty: base samples N per damper and family "
        "(Saltelli design: N (D + 2) cases; a power of 2; a larger N reuses a smaller)",
        "uncertainty",
        lo=2,
        hi=1 << 20,
        power_of_2=True,
    )
    uq_seed: int = option(
        "int",
        2026,
        "uncertainty: seed of the scrambled Sobol sequence",
        "uncertainty",
        lo=0,
        hi=2**31 - 1,
    )
    uq_threshold: float | None = option(
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
    )
    uq_schedule: str = option(
        "str",
        "dynamic",
        "uncertainty: how samples spread over MPI ranks: "
        "dynamic (a shared counter, each rank takes the next sample when free) or static "
        "(round-robin, for comparison)",
        "uncertainty",
        choices=("dynamic", "static"),
    )


# the physical range of each uncertain input's distribution (None: unbounded above)
UQ_VALID = {
    "mu": (0.0, 2.0),
    "cf": (0.0, None),
    "kt": (0.0, None),
    "kn": (0.0, None),
    "damping": (0.0, 0.5),
    "seat-tilt": (-5.0, 5.0),
}


def uq_distribution(spec: Any, name: str):
    """The distribution of uncertain input ``name`` (``uq-<name>``), checked against its
    physical range (:data:`UQ_VALID`): a ``workbench.post.uncertainty.Distribution``."""
    from ....post.uncertainty import parse_distribution

    opt = f"uq-{name}"
    text = getattr(spec.uncertainty, opt.replace("-", "_"))
    d = parse_distribution(opt, text)
    lo, hi = d.support
    vlo, vhi = UQ_VALID[name]
    if (
        lo < vlo
        or (vlo == 0.0 and name in ("cf", "kt", "kn") and lo <= 0.0)
        or (vhi is not None and hi > vhi)
    ):
        raise InputError(
            opt,
            text,
            f"a distribution within [{vlo:g}, {vhi if vhi is not None else 'inf'}] (give bounds)",
        )
    return d


def check(spec: Any) -> None:
    """Every uncertain input's distribution parses and stays in its physical range."""
    for name in UQ_VALID:
        uq_distribution(spec, name)

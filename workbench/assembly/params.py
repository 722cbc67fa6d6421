"""Contact parameters shared by the FE stage (stuck springs) and the studies.

Stiffnesses and preload are given per unit of contact extent, as in the
study of the conical damper: per metre of contact line for the cone and
cylinder, per square metre of contact face for the wedge. A pair's own
value is the per-unit value times its tributary weight
(``ContactSet.weight``: a length or an area).
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace
from pathlib import Path

import numpy as np

from ..config import load_record, param, read_toml
from ..contact.law_params import COMMON, LawParam, law_params
from ..errors import check_range

DEFAULT_FILE = Path(__file__).resolve().parents[2] / "geometry" / "contact.toml"
# the contact laws' parameters (workbench/contact/laws/): "mu", every law's, is the field
# ``mu``; a law's own parameters are the mapping ``law``
_MU = next(p for p in COMMON if p.name == "mu")
_OWN = tuple(p for p in law_params() if p not in COMMON)


@dataclass(frozen=True)
class ContactParams:
    """Friction contact parameters (file keys carry their units)."""

    mu: float = param(_MU.default, _MU.help, lo=_MU.lo, hi=_MU.hi)
    kt_line_n_per_m2: float = param(
        5.0e8,
        "tangential stiffness per metre of contact line (cone, cylinder), N/m per m",
        lo=0.0,
        lo_open=True,
    )
    kn_line_n_per_m2: float = param(
        5.0e8,
        "normal stiffness per metre of contact line (cone, cylinder), N/m per m",
        lo=0.0,
        lo_open=True,
    )
    kt_face_n_per_m3: float = param(
        5.0e10,
        "tangential stiffness per square metre of contact face (wedge), N/m per m^2",
        lo=0.0,
        lo_open=True,
    )
    kn_face_n_per_m3: float = param(
        5.0e10,
        "normal stiffness per square metre of contact face (wedge), N/m per m^2",
        lo=0.0,
        lo_open=True,
    )
    cf_n: float = param(300.0, "centrifugal force on the damper (radial, +z), N", lo=0.0)
    # each contact law's own parameters (beyond mu) by name: declared in its module, given in
    # [contact] under that name; every declared one is here (its default when unset)
    law: dict[str, float] = field(default_factory=dict, hash=False)

    def law_param(self, name: str) -> float:
        """The value of contact-law parameter ``name`` (``mu`` or a law's own)."""
        return self.mu if name == "mu" else self.law[name]

    def key(self) -> dict:
        """The record as a cache key: its fields, the laws' own parameters only when some
        law declares any (so the keys of the laws without stay what they were)."""
        d = {f.name: getattr(self, f.name) for f in fields(self) if f.name != "law"}
        return {**d, "law": dict(self.law)} if self.law else d

    def pair_stiffness(self, kind: str, weight: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(kt, kn) in N/m for each pair of a ContactSet of ``kind`` with ``weight``."""
        w = np.asarray(weight, dtype=float)
        if kind == "line":
            return self.kt_line_n_per_m2 * w, self.kn_line_n_per_m2 * w
        if kind == "face":
            return self.kt_face_n_per_m3 * w, self.kn_face_n_per_m3 * w
        raise ValueError(f"{kind=} is not 'line' or 'face'")


def load_contact_params(
    path: str | Path | None = None, *, geometry_file: str | Path | None = None, **overrides: float
) -> ContactParams:
    """Contact parameters, layered: geometry/contact.toml < the ``[contact]`` table of a
    rig file (``geometry_file``: a rig calibrated with its own contact) < ``path`` (a
    contact file) < ``overrides`` (None values ignored)."""
    data, _ = _layers(path, geometry_file, overrides)
    own = {p.name: _law_value(p, data.pop(p.name, p.default)) for p in _OWN}
    return replace(load_record(ContactParams, data, "contact."), law=own)


def _law_value(p: LawParam, value: object) -> float:
    return check_range(f"contact.{p.name}", value, p.lo, p.hi, lo_open=p.lo_open, unit=p.unit)


def contact_sources(
    path: str | Path | None = None, *, geometry_file: str | Path | None = None, **overrides: float
) -> dict[str, str]:
    """Where each field of :func:`load_contact_params` (same arguments) comes from.

    Field name -> "option" (an override), a file and its table
    (``"<file> [contact]"``, the path as given) or "ContactParams default".
    """
    _, src = _layers(path, geometry_file, overrides)
    names = [*(f.name for f in fields(ContactParams) if f.name != "law"), *(p.name for p in _OWN)]
    return {n: src.get(n, "ContactParams default") for n in names}


def _layers(path, geometry_file, overrides) -> tuple[dict, dict[str, str]]:
    """The merged ``[contact]`` values and, per key, the layer that set it."""
    data: dict = {}
    src: dict[str, str] = {}
    for source in (DEFAULT_FILE if DEFAULT_FILE.is_file() else None, geometry_file, path):
        if source is not None:
            table = read_toml(source).get("contact", {})
            data.update(table)
            src.update({k: f"{source} [contact]" for k in table})
    given = {k: v for k, v in overrides.items() if v is not None}
    data.update(given)
    src.update({k: "option" for k in given})
    return data, src

"""The contact laws' parameters, each declared once with its unit, range and default.

Every law reads the friction coefficient ``mu`` (:data:`COMMON`: the slip
limit is ``mu N``). A law module of :mod:`workbench.contact.laws` may declare
parameters of its own beside ``NAME`` and ``N_STATE``: ``PARAMS``, a tuple of
plain dicts with the fields of :class:`LawParam`::

    PARAMS = (
        {"name": "eta", "help": "...", "unit": "", "lo": 0.0, "hi": 1.0, "default": 0.1},
    )

read from its source (numba stays unloaded). The study options (``--mu``,
``--<name>``: :data:`workbench.study_options.LAW_OPTIONS`), the contact
parameter files (``[contact] <name>`` of ``geometry/contact.toml``), the
contact parameters record (:class:`workbench.assembly.params.ContactParams`:
``mu``, and a law's own in ``law``), the assembly (one value per contact pair:
``AssembledModel.mu`` and ``AssembledModel.law``), the model's cache key and
the report's Inputs table read them here (:func:`law_params`). Per contact
element they reach the law's ``step`` as the row ``lp`` (its own parameters in
the order of ``PARAMS``, :func:`own_params`; ``mu`` is an argument of its own).
"""

from __future__ import annotations

import ast
from dataclasses import dataclass
from functools import cache
from pathlib import Path

from .laws import LAWS, REGISTRY


@dataclass(frozen=True)
class LawParam:
    """One parameter of a contact law (per contact element, a float)."""

    name: str  # the study option, the [contact] key and the report's key, e.g. "mu"
    help: str  # what it is, for --help and the report ("friction coefficient")
    unit: str = ""  # "" for a pure number
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    default: float = 0.0  # when neither the contact files nor the study set it


# the parameters every law reads (``step``'s ``mu``: the slip limit is mu N)
COMMON: tuple[LawParam, ...] = (
    LawParam("mu", "friction coefficient", lo=0.0, hi=2.0, default=0.5),
)


@cache
def _own(module_name: str) -> tuple[LawParam, ...]:
    """The ``PARAMS`` a law module declares (read from its source)."""
    path = Path(__file__).parent / "laws" / f"{module_name}.py"
    for node in ast.parse(path.read_text()).body:
        if (
            isinstance(node, ast.Assign)
            and len(node.targets) == 1
            and isinstance(node.targets[0], ast.Name)
            and node.targets[0].id == "PARAMS"
        ):
            try:
                return tuple(LawParam(**p) for p in ast.literal_eval(node.value))
            except (TypeError, ValueError) as e:
                raise ImportError(f"contact law module {path.name}: PARAMS: {e}") from None
    return ()


def params_of(law: str) -> tuple[LawParam, ...]:
    """The parameters law ``law`` reads: the common ones, then its own."""
    return (*COMMON, *own_params(law))


def own_params(law: str) -> tuple[LawParam, ...]:
    """Law ``law``'s own parameters, in the order of its ``PARAMS``: the columns of the
    per-element array ``lp`` its ``step`` receives (``lp[j]``: the ``j``-th)."""
    return _own(REGISTRY[law].module_name)


def _all_params() -> tuple[LawParam, ...]:
    out: dict[str, LawParam] = {}
    for name in LAWS:
        for p in params_of(name):
            if out.setdefault(p.name, p) != p:
                raise ImportError(
                    f"contact law '{name}' declares the parameter '{p.name}' unlike another "
                    "law: one name, one declaration (same help, unit, range and default)"
                )
    return tuple(out.values())


_PARAMS = _all_params()


def law_params() -> tuple[LawParam, ...]:
    """Every parameter of every registered law: the common ones, then each law's own."""
    return _PARAMS

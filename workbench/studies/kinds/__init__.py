"""The registry of study kinds: one folder per kind in this package, found by name.

A kind is a package ``workbench/studies/kinds/<name>/`` whose ``__init__.py``
defines ``KIND = StudyKind(...)``: its name, a one-line description, the
function that runs a study of that kind, its own study options (declared
once, in the kind's ``options.py``) and the checks of their consistency.
Its computing, figures and report modules sit beside it in the folder.
Nothing else names a kind: ``upd study`` (its ``--kind`` choices and
``--help``), the study specification and the report ask this registry
(:func:`names`, :func:`get`). Packages are found by :mod:`pkgutil` on first
use; a kind's ``__init__.py`` imports only its options, so listing the kinds
imports no solver.
"""

from __future__ import annotations

import importlib
import pkgutil
from collections.abc import Callable
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

from ...errors import check_choice
from ...study_options import SHOWN, Option, SharedOptions, declare, input_table, options_of


@dataclass(frozen=True)
class StudyKind:
    """One study kind: what ``upd study`` needs to know to offer and run it.

    ``run(spec, out, force)`` computes the study into the folder ``out``
    (cases, tables, figures, ``report.html``) and returns the JSON summary
    ``upd study --json`` prints. ``options`` is the record of the kind's own
    study options (a frozen dataclass whose fields are declared with
    :func:`workbench.study_options.option`; a study reads them as
    ``spec.<kind>.<field>``). Every kind's options are accepted and checked in
    every study, so a typo in one is refused whatever the kind; ``check(spec)``
    refuses an inconsistent combination of them with an ``InputError``.
    """

    name: str  # the value of the study option ``kind``; the package's name
    description: str  # one line, for ``upd study --help`` and the report
    run: Callable[[Any, Path, bool], dict[str, Any]]
    options: type | None = None  # the record of its own options
    check: Callable[[Any], None] | None = None
    order: int = 100  # place in the kind list (the built-in kinds first)
    # the shared options (or another kind's it reads) its report's Inputs table lists before
    # its own (then the model's and the solver's follow: workbench.study_options.input_table)
    shows: tuple[str, ...] = SHOWN
    # model and solver options the kind does not read: left out of its Inputs table, so the
    # table states only what the run used (e.g. the rig's "modes" on a disk sector)
    ignores: tuple[str, ...] = ()

    @property
    def declared(self) -> tuple[Option, ...]:
        """Its own study options, in field order."""
        return () if self.options is None else options_of(self.options)


_REGISTRY: dict[str, StudyKind] | None = None


def _discover() -> dict[str, StudyKind]:
    found = []
    for info in pkgutil.iter_modules(__path__):
        if info.name.startswith("_") or not info.ispkg:
            continue
        mod = importlib.import_module(f"{__name__}.{info.name}")
        kind = getattr(mod, "KIND", None)
        if isinstance(kind, StudyKind):
            if kind.name != info.name:
                raise RuntimeError(
                    f"{mod.__name__}: KIND.name is '{kind.name}', expected "
                    f"'{info.name}' (the package's name)"
                )
            taken = {f.name for f in fields(SharedOptions)} | {"law", "kinds", "source"}
            if kind.options is not None and info.name in taken:  # spec.<kind> is its record
                raise RuntimeError(
                    f"{mod.__name__}: a kind with options of its own may not share its "
                    f"name with a field of the study spec ({info.name})"
                )
            found.append(kind)
            declare(kind.declared)  # figure labels find a kind's option (study_options.find)
    found.sort(key=lambda k: (k.order, k.name))
    return {k.name: k for k in found}


def all_kinds() -> tuple[StudyKind, ...]:
    """Every registered kind, in list order."""
    global _REGISTRY
    if _REGISTRY is None:
        _REGISTRY = _discover()
    return tuple(_REGISTRY.values())


def names() -> tuple[str, ...]:
    """The kind names, in order (comparison, sweep, fidelity, ..., then any added kind)."""
    return tuple(k.name for k in all_kinds())


def get(name: str, param: str = "kind") -> StudyKind:
    """The kind called ``name``; InputError naming ``param`` if there is none."""
    kinds = {k.name: k for k in all_kinds()}
    return kinds[check_choice(param, name, tuple(kinds))]


def kind_options() -> tuple[Option, ...]:
    """Every registered kind's own options, kind by kind."""
    return tuple(o for k in all_kinds() for o in k.declared)


def inputs_table(name: str) -> tuple[tuple[str, str], ...]:
    """The rows ``(option, unit)`` of the Inputs table of a study of kind ``name``: the
    options it shows (``shows``), its own options, the model's and the solver's but for
    those it ignores (``ignores``)."""
    kind = get(name)
    return tuple(r for r in input_table(kind.shows, kind.declared) if r[0] not in kind.ignores)


def rediscover() -> tuple[str, ...]:
    """Search the package again (after a kind was added at run time); the names."""
    global _REGISTRY
    _REGISTRY = None
    return names()


__all__ = [
    "StudyKind",
    "all_kinds",
    "get",
    "inputs_table",
    "kind_options",
    "names",
    "rediscover",
]

"""The contact laws: one module each, found here without edits elsewhere.

A law is a module of this package that defines

* ``NAME`` (str): the name used in model files (``law = "..."``);
* ``N_STATE`` (int): the size of its history state ``s`` per element;
* ``step`` (numba ``njit``): one time sample of one element,

  ``step(u, s, mu, kt1, kt2, kn, n0, want_jac, f, s_new, Fu, Fs, Su, Ss) -> flag``

  from the local relative displacement ``u = [u1, u2, un]`` (m, ``un > 0``
  opening) at this sample and the state ``s`` after the previous one, it
  writes the force ``f = [T1, T2, -N]`` (N) and the new state ``s_new``,
  and when ``want_jac`` their derivatives ``Fu = df/du`` (3, 3),
  ``Fs = df/ds`` (3, N_STATE), ``Su = ds_new/du`` (N_STATE, 3),
  ``Ss = ds_new/ds`` (N_STATE, N_STATE); it returns 0 (stuck), 1
  (slipping) or 2 (separated). The rest state is ``s = 0`` (no force, the
  slider at ``u = 0``).

The generic march (:mod:`workbench.contact.march`) runs any law over
periods of samples until the state repeats and chains the derivatives;
the time integration calls ``step`` once per time step. Adding a law is
adding one module here (see ``dahl.py``).
"""

from __future__ import annotations

import importlib
import pkgutil
from dataclasses import dataclass
from types import ModuleType


@dataclass(frozen=True)
class Law:
    """A registered contact law (see the package docstring)."""

    name: str
    n_state: int
    step: object  # numba dispatcher
    summary: str
    module: ModuleType


def _discover() -> dict[str, Law]:
    found: dict[str, Law] = {}
    mods = sorted(m.name for m in pkgutil.iter_modules(__path__) if not m.name.startswith("_"))
    for name in mods:
        mod = importlib.import_module(f"{__name__}.{name}")
        doc = (mod.__doc__ or "").strip().splitlines()
        law = Law(mod.NAME, int(mod.N_STATE), mod.step, doc[0] if doc else "", mod)
        found[law.name] = law
    return found


REGISTRY: dict[str, Law] = _discover()
# "decoupled" first: the default and the code 0 of older records
LAWS: tuple[str, ...] = tuple(
    sorted(REGISTRY, key=lambda n: (n != "decoupled", n != "circular", n))
)


def get_law(name: str) -> Law:
    """The registered law ``name`` (InputError with the choices otherwise)."""
    law = REGISTRY.get(name)
    if law is None:
        from ...errors import check_choice

        check_choice("law", name, LAWS)
    return law

"""The contact laws: one module each, found here without edits elsewhere.

A law is a module of this package that defines

* ``NAME`` (str): the name used in model files (``law = "..."``);
* ``N_STATE`` (int): the size of its history state ``s`` per element;
* ``step`` (numba ``njit``): one time sample of one element,

  ``step(u, s, mu, kt1, kt2, kn, n0, lp, want_jac, f, s_new, Fu, Fs, Su, Ss) -> flag``

  from the local relative displacement ``u = [u1, u2, un]`` (m, ``un > 0``
  opening) at this sample and the state ``s`` after the previous one, with
  the element's parameters (``mu``, ``kt1``, ``kt2``, ``kn``, ``n0``, and
  ``lp``: a float array of the law's own parameters in the order of its
  ``PARAMS``, empty for a law without, see :mod:`workbench.contact.law_params`), it
  writes the force ``f = [T1, T2, -N]`` (N) and the new state ``s_new``,
  and when ``want_jac`` their derivatives ``Fu = df/du`` (3, 3),
  ``Fs = df/ds`` (3, N_STATE), ``Su = ds_new/du`` (N_STATE, 3),
  ``Ss = ds_new/ds`` (N_STATE, N_STATE); it returns 0 (stuck), 1
  (slipping) or 2 (separated). The rest state is ``s = 0`` (no force, the
  slider at ``u = 0``).

The generic march (:mod:`workbench.contact.march`) runs any law over
periods of samples until the state repeats and chains the derivatives;
the time integration calls ``step`` once per time step. Adding a law is
adding one module here (see ``dahl.py``), with parameters of its own too
(``PARAMS``: the march, the time integrations and the compiled kernels pass
them to ``step`` as ``lp``).
"""

from __future__ import annotations

import ast
import importlib
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType

# A sample counts as slipping (for the status only; the force is limited
# either way) when the trial force exceeds the slip limit by more than this
# fraction of it. In the converged period an element that slipped only while
# the march started (elastic shakedown) touches its limit again to round-off,
# ~1e-15 relative, without slipping: it is stuck.
SLIP_TOL = 1e-9


@dataclass(frozen=True)
class Law:
    """A registered contact law (see the package docstring).

    Its name, state size and summary are read from the module's source; the
    module itself (and numba with it) is imported when ``step`` or ``module``
    is first used, so a run whose kernels are compiled ahead of time never
    imports numba.
    """

    name: str
    n_state: int
    summary: str
    module_name: str
    _mod: list = field(default_factory=list, repr=False, compare=False)

    @property
    def module(self) -> ModuleType:
        if not self._mod:
            self._mod.append(importlib.import_module(f"{__name__}.{self.module_name}"))
        return self._mod[0]

    @property
    def step(self) -> object:
        """The numba dispatcher of one time sample (see the package docstring)."""
        return self.module.step


def _constants(path: Path) -> tuple[dict[str, object], str]:
    """The module-level constants (NAME, N_STATE) and the docstring of a law's source."""
    tree = ast.parse(path.read_text())
    out: dict[str, object] = {}
    for node in tree.body:
        if isinstance(node, ast.Assign) and len(node.targets) == 1:
            t = node.targets[0]
            if isinstance(t, ast.Name) and t.id in ("NAME", "N_STATE"):
                out[t.id] = ast.literal_eval(node.value)
    return out, ast.get_docstring(tree) or ""


def _discover() -> dict[str, Law]:
    found: dict[str, Law] = {}
    here = Path(__file__).parent
    for path in sorted(here.glob("*.py")):
        if path.name.startswith("_"):
            continue
        const, doc = _constants(path)
        if "NAME" not in const or "N_STATE" not in const:
            raise ImportError(f"contact law module {path.name} must define NAME and N_STATE")
        lines = doc.strip().splitlines()
        law = Law(str(const["NAME"]), int(const["N_STATE"]), lines[0] if lines else "", path.stem)
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

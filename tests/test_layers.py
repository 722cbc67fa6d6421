"""The shape of the package: the figures and tables never import a study; modules stay short.

``workbench.render`` draws and writes what it is given (post-processed
records and plain data); ``workbench.post`` computes those records. Neither
imports ``workbench.studies`` (which imports them): no import circle. The
check reads the sources (``ast``), so it also sees imports inside functions.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parents[1] / "workbench"


def imported_modules(source: str, module: str) -> list[tuple[int, str]]:
    """(line, absolute module name) of every import in ``source``, the source of the
    module named ``module`` (e.g. "workbench.render.sections"); relative imports resolved."""
    package = module.split(".")[:-1]
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            out.extend((node.lineno, a.name) for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - (node.level - 1)]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            out.append((node.lineno, mod))
            # "from .. import studies" names the sub-package itself
            out.extend((node.lineno, f"{mod}.{a.name}") for a in node.names)
    return out


def _is_studies(mod: str) -> bool:
    return mod == "workbench.studies" or mod.startswith("workbench.studies.")


@pytest.mark.parametrize("layer", ["render", "post"])
def test_layer_never_imports_studies(layer):
    bad = []
    for p in sorted((PKG / layer).glob("*.py")):
        module = ".".join(p.relative_to(PKG.parent).with_suffix("").parts)
        bad += [
            f"{p.relative_to(PKG.parent)}:{line}: {mod}"
            for line, mod in imported_modules(p.read_text(), module)
            if _is_studies(mod)
        ]
    assert not bad, f"workbench/{layer} imports workbench.studies:\n" + "\n".join(bad)


def test_the_scan_sees_relative_local_and_package_imports():
    """A check of the check: every way of writing such an import is caught."""
    src = (
        "import workbench.studies.spec\n"
        "from .. import studies\n"
        "def f():\n"
        "    from ..studies.spec import BY_NAME\n"
        "    return BY_NAME\n"
        "from .common import pyplot\n"
    )
    mods = imported_modules(src, "workbench.render.x")
    assert sorted({line for line, m in mods if _is_studies(m)}) == [1, 2, 4]
    assert (6, "workbench.render.common") in mods


MAX_LINES = 600  # a module a newcomer can hold in their head (issue 14)


def test_no_module_is_over_600_lines():
    long = {
        str(p.relative_to(PKG.parent)): n
        for p in sorted(PKG.rglob("*.py"))
        if (n := len(p.read_text().splitlines())) > MAX_LINES
    }
    assert not long, f"modules over {MAX_LINES} lines (split them by concept): {long}"


def test_nonlinear_mode_sources_do_not_key_the_forced_responses():
    """Every nonlinear-mode module of hbm/ is left out of the forced-response cache key
    (an edit to the backbone code must not recompute a study's cases), and none of the
    modules that do key it imports one of them."""
    import ast

    from workbench.studies.plan import NLMODE_SOURCES

    hbm = PKG / "hbm"
    names = {p.name for p in hbm.glob("*.py")}
    nl = {n for n in names if n.startswith(("nlmode", "epmc")) or n == "synthesis.py"}
    assert nl == set(NLMODE_SOURCES)
    stems = {n[:-3] for n in nl}
    for n in sorted(names - nl):
        tree = ast.parse((hbm / n).read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.module and node.level == 1:
                assert node.module.split(".")[0] not in stems, (n, node.module)

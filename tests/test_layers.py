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


def from_module(node: ast.ImportFrom, module: str) -> str:
    """The absolute name of the module a ``from ... import`` in ``module`` reads."""
    if not node.level:
        return node.module or ""
    package = module.split(".")[:-1]
    base = package[: len(package) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def imported_modules(source: str, module: str) -> list[tuple[int, str]]:
    """(line, absolute module name) of every import in ``source``, the source of the
    module named ``module`` (e.g. "workbench.render.sections"); relative imports resolved."""
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            out.extend((node.lineno, a.name) for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            mod = from_module(node, module)
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


def test_a_kinds_figures_and_report_take_plain_records():
    """A study kind's folder holds its figures and report beside its computing; those two
    draw what they are given, as ``render/`` does: they import ``render/``, ``post/`` and
    each other, never the study engine, a kind's computing or another kind."""
    bad = []
    for p in sorted((PKG / "studies" / "kinds").glob("*/*.py")):
        if p.stem not in ("figures", "report"):
            continue
        module = ".".join(p.relative_to(PKG.parent).with_suffix("").parts)
        own = module.rpartition(".")[0]
        bad += [
            f"{p.relative_to(PKG.parent)}:{line}: {mod}"
            for line, mod in imported_modules(p.read_text(), module)
            if _is_studies(mod)
            and not mod.startswith((f"{own}.figures", f"{own}.report"))
            and mod != own  # "from . import figures"
        ]
    assert not bad, "a kind's figures or report import a study module:\n" + "\n".join(bad)


def test_the_scan_sees_relative_local_and_package_imports():
    """A check of the check: every way of writing such an import is caught."""
    src = (
        "import workbench.studies.engine.spec\n"
        "from .. import studies\n"
        "def f():\n"
        "    from ..studies.spec import BY_NAME\n"
        "    return BY_NAME\n"
        "from .common import pyplot\n"
    )
    mods = imported_modules(src, "workbench.render.x")
    assert sorted({line for line, m in mods if _is_studies(m)}) == [1, 2, 4]
    assert (6, "workbench.render.common") in mods


# the layers post/ is built on (post/ computes records from what they produce); pipeline/ is
# not one of them yet: it imports post.results (CaseResult) and post.provenance
BELOW_POST = ("io", "geometry", "fe", "assembly", "contact", "hbm", "reduced.py")


def _is_post(mod: str) -> bool:
    return mod == "workbench.post" or mod.startswith("workbench.post.")


@pytest.mark.parametrize("layer", BELOW_POST)
def test_layers_below_post_never_import_post(layer):
    """post/ serves the study and report layers only: units, VTK and CSV writers and the
    HDF5 record writer live in io/, so no module below post/ imports it (issue 30)."""
    top = PKG / layer
    files = [top] if top.suffix == ".py" else sorted(top.rglob("*.py"))
    assert files and all(p.is_file() for p in files), f"workbench/{layer} is not there"
    bad = []
    for p in files:
        module = ".".join(p.relative_to(PKG.parent).with_suffix("").parts)
        if p.name == "__init__.py":
            module += ".__init__"
        bad += [
            f"{p.relative_to(PKG.parent)}:{line}: {mod}"
            for line, mod in imported_modules(p.read_text(), module)
            if _is_post(mod)
        ]
    assert not bad, f"workbench/{layer} imports workbench.post:\n" + "\n".join(bad)


MAX_LINES = 600  # a module a newcomer can hold in their head (issue 14)


def test_no_module_is_over_600_lines():
    long = {
        str(p.relative_to(PKG.parent)): n
        for p in sorted(PKG.rglob("*.py"))
        if (n := len(p.read_text().splitlines())) > MAX_LINES
    }
    assert not long, f"modules over {MAX_LINES} lines (split them by concept): {long}"


def test_nonlinear_mode_sources_do_not_key_the_forced_responses():
    """Everything under hbm/nlmodes/ is left out of the forced-response cache key (an edit
    to the backbone code must not recompute a study's cases), and no module of hbm/
    outside it imports it (so nothing that keys a forced response runs backbone code)."""
    from workbench.studies.engine.plan import NLMODE_PACKAGE

    hbm = PKG / "hbm"
    nl = hbm / NLMODE_PACKAGE
    assert (nl / "backbone.py").is_file()  # the package the rule names is there
    bad = []
    for p in sorted(hbm.rglob("*.py")):
        if nl in p.parents:
            continue
        module = ".".join(p.relative_to(PKG.parent).with_suffix("").parts)
        bad += [
            f"{p.relative_to(PKG.parent)}:{line}: {mod}"
            for line, mod in imported_modules(p.read_text(), module)
            if mod.startswith(f"workbench.hbm.{NLMODE_PACKAGE}")
        ]
    assert not bad, "forced-response modules import the nonlinear modes:\n" + "\n".join(bad)


# ---- no import cycle in the package (issue 30) ----------------------------------------------
def _modules(pkg: Path) -> dict[str, Path]:
    """Module name -> source file of every module of ``pkg`` (a package: its __init__)."""
    out = {}
    for p in sorted(pkg.rglob("*.py")):
        parts = p.relative_to(pkg.parent).with_suffix("").parts
        out[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = p
    return out


def import_graph(pkg: Path) -> dict[str, set[str]]:
    """module -> the package's modules it imports (imports inside functions included).

    A package is the module of its ``__init__.py``; an import of ``a.b.name``
    where ``name`` is not a module counts as an import of ``a.b``. A module's
    imports of its own parent packages do not count (Python imports them first
    anyway, and they hold no code of the module's concept).
    """
    mods = _modules(pkg)

    def resolve(m: str) -> str:
        while m and m not in mods:
            m = m.rpartition(".")[0]
        return m

    graph: dict[str, set[str]] = {m: set() for m in mods}
    for m, p in mods.items():
        name = m + ".__init__" if p.name == "__init__.py" else m
        for _, t in imported_modules(p.read_text(), name):
            r = resolve(t)
            if r and r != m and not m.startswith(r + "."):
                graph[m].add(r)
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on.add(root)
        while work:
            v, it = work[-1]
            w = next(it, None)
            if w is not None:
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(graph[w]))))
                elif w in on:
                    low[v] = min(low[v], index[w])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                comp = []
                while True:
                    w = stack.pop()
                    on.discard(w)
                    comp.append(w)
                    if w == v:
                        break
                if len(comp) > 1:
                    out.append(sorted(comp))
    return out


def test_no_import_cycle_in_the_package():
    found = cycles(import_graph(PKG))
    assert not found, "import cycles (each a set of modules that import each other):\n" + "\n".join(
        ", ".join(c) for c in found
    )


def test_the_cycle_check_finds_a_cycle_through_a_function_level_import(tmp_path):
    """A check of the check: a cycle closed only by an import inside a function is found,
    a chain is not."""
    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "sub" / "__init__.py").write_text("")
    (pkg / "a.py").write_text("from .sub import b\n")
    (pkg / "sub" / "b.py").write_text("def f():\n    from ..c import g\n    return g\n")
    (pkg / "c.py").write_text("X = 1\n")
    assert cycles(import_graph(pkg)) == []
    (pkg / "c.py").write_text("def g():\n    from . import a\n    return a\n")
    assert cycles(import_graph(pkg)) == [["pkg.a", "pkg.c", "pkg.sub.b"]]


# ---- no re-export shims (issue 30) -------------------------------------------------------------
ROOT = PKG.parent


def _top_level(path: Path) -> tuple[set[str], set[str]]:
    """(names a module defines, names it imports) at its top level (inside if/try too)."""
    defined: set[str] = set()
    imported: set[str] = set()

    def visit(body):
        for node in body:
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                defined.add(node.name)
            elif isinstance(node, ast.Assign):
                defined.update(
                    n.id for t in node.targets for n in ast.walk(t) if isinstance(n, ast.Name)
                )
            elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
                defined.add(node.target.id)
            elif isinstance(node, (ast.Import, ast.ImportFrom)):
                imported.update((a.asname or a.name).split(".")[0] for a in node.names)
            elif isinstance(node, (ast.If, ast.Try)):
                visit(node.body)
                visit(node.orelse)
                for h in getattr(node, "handlers", []):
                    visit(h.body)
                visit(getattr(node, "finalbody", []))

    visit(ast.parse(path.read_text()).body)
    return defined, imported


def reexports(pkg: Path, users: list[Path]) -> list[str]:
    """Imports of a name from a module (not a package) that only imports it, and names a
    module's ``__all__`` lists without defining them: a re-export shim either way."""
    mods = _modules(pkg)
    tops = {m: _top_level(p) for m, p in mods.items() if p.name != "__init__.py"}
    bad = []
    for m, p in mods.items():
        if m not in tops:
            continue
        for node in ast.parse(p.read_text()).body:
            if isinstance(node, (ast.Assign, ast.AugAssign)) and isinstance(
                node.value, (ast.List, ast.Tuple)
            ):
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                if any(isinstance(t, ast.Name) and t.id == "__all__" for t in targets):
                    defined, imported = tops[m]
                    bad += [
                        f"{p.relative_to(pkg.parent)}: __all__ lists {e.value!r}, imported"
                        for e in node.value.elts
                        if isinstance(e, ast.Constant)
                        and e.value not in defined
                        and e.value in imported
                    ]
    for f in users:
        me = ".".join(f.relative_to(pkg.parent).with_suffix("").parts)
        for node in ast.walk(ast.parse(f.read_text())):
            if not isinstance(node, ast.ImportFrom):
                continue
            mod = from_module(node, me)
            if mod not in tops:
                continue
            defined, imported = tops[mod]
            bad += [
                f"{f.relative_to(pkg.parent)}:{node.lineno}: {a.name} from {mod}, "
                "which only imports it"
                for a in node.names
                if a.name not in defined and a.name in imported and f"{mod}.{a.name}" not in mods
            ]
    return bad


def test_no_name_is_imported_through_a_module_that_only_imports_it():
    users = [
        p
        for d in ("workbench", "tests", "benchmarks", "examples")
        for p in sorted((ROOT / d).rglob("*.py"))
    ]
    bad = reexports(PKG, users)
    assert not bad, "re-exports (import from the module that defines the name):\n" + "\n".join(bad)


def test_the_reexport_check_finds_both_kinds(tmp_path):
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("from .a import f\n")  # a package may gather its names
    (pkg / "a.py").write_text("def f():\n    pass\n")
    (pkg / "b.py").write_text("from .a import f\n__all__ = ['f', 'g']\ndef g():\n    return f()\n")
    (pkg / "c.py").write_text("from .b import f, g\nfrom . import f as h\n")
    bad = reexports(pkg, sorted(pkg.glob("*.py")))
    assert bad == [
        "pkg/b.py: __all__ lists 'f', imported",
        "pkg/c.py:1: f from pkg.b, which only imports it",
    ]

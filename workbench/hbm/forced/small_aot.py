"""The compiled small-system corrector ahead of time: one extension module, no numba at run time.

``python -m workbench.hbm.forced.small_aot`` (run by scripts/setup.sh) compiles
:func:`workbench.hbm.forced.small_kernels.solve_flat` once per contact law with
numba's ahead-of-time compiler into ``workbench/hbm/_small_aot*.so``, with
a digest of the sources it was built from (the kernels, the contact
march, every law, the numba version). :func:`load` uses it only when the
digest still matches; otherwise :mod:`.small` compiles the same kernels
just in time (numba, cached on disk). Loading the module costs
milliseconds, where importing numba costs about 0.2 s of CPU: it is what
keeps a small ``upd frf`` run lean.
"""

from __future__ import annotations

import hashlib
import importlib
import sys
import types
from pathlib import Path

MODULE = "_small_aot"
_HERE = Path(__file__).resolve().parent
_loaded: dict[str, object] = {}


def sources() -> list[Path]:
    """The files the compiled kernels depend on."""
    contact = _HERE.parents[1] / "contact"
    laws = sorted((contact / "laws").glob("*.py"))
    return [_HERE / "small_kernels.py", contact / "march.py", *laws]


def digest() -> int:
    """A 62-bit digest of the sources and the numba version (without importing numba)."""
    from importlib.metadata import PackageNotFoundError, version

    h = hashlib.sha256()
    for p in sources():
        h.update(p.name.encode())
        h.update(p.read_bytes())
    try:
        h.update(version("numba").encode())
    except PackageNotFoundError:
        h.update(b"no numba")
    return int.from_bytes(h.digest()[:8], "little") >> 2


def load(law: str, what: str = "solve"):
    """The ahead-of-time compiled ``solve`` (or ``evaluate``) for ``law``, or None (not built,
    or out of date)."""
    if "mod" not in _loaded:
        mod = None
        try:
            mod = importlib.import_module(f"{__package__}.{MODULE}")
            if int(mod.source_digest()) != digest():
                mod = None
        except (ImportError, AttributeError, OSError):
            mod = None
        _loaded["mod"] = mod
    mod = _loaded["mod"]
    return getattr(mod, f"{what}_{law}", None) if mod is not None else None


def build(force: bool = False) -> Path | None:
    """Compile the module (one solver per law) unless an up-to-date one exists. Returns its path."""
    import warnings

    if not force and load("decoupled") is not None:
        return None
    from numba import njit

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        from numba.pycc import CC

    from ...contact.laws import REGISTRY
    from ...contact.march import _march_py
    from . import small_kernels as K

    cc = CC(MODULE)
    cc.output_dir = str(_HERE)
    cc.verbose = False
    names = [n for n, v in vars(K).items() if isinstance(v, types.FunctionType)]
    for law_name, law in sorted(REGISTRY.items()):
        g = dict(vars(K))
        mg = dict(_march_py.__globals__)
        mg["step"] = law.step
        g["march"] = njit(types.FunctionType(_march_py.__code__, mg, f"_march_aot_{law_name}"))
        for name in names:
            f = getattr(K, name)
            g[name] = njit(types.FunctionType(f.__code__, g, f"{name}_aot_{law_name}"))
        entry = types.FunctionType(K.solve_flat.__code__, g, f"solve_{law_name}")
        cc.export(f"solve_{law_name}", K.SIGNATURE)(entry)
        entry = types.FunctionType(K.evaluate_flat.__code__, g, f"evaluate_{law_name}")
        cc.export(f"evaluate_{law_name}", K.EVAL_SIGNATURE)(entry)
    ns: dict = {}
    exec(f"def source_digest():\n    return {digest()}\n", ns)  # the digest as a constant
    cc.export("source_digest", "i8()")(ns["source_digest"])
    cc.compile()
    _loaded.clear()
    importlib.invalidate_caches()
    out = [p for p in _HERE.glob(f"{MODULE}*.so")]
    return out[0] if out else None


def main(argv: list[str] | None = None) -> int:
    import argparse

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--force", action="store_true", help="rebuild even when up to date")
    a = ap.parse_args(argv)
    path = build(force=a.force)
    print(f"small_aot: {'built ' + str(path) if path else 'up to date'}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

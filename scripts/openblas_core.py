"""Pick OpenBLAS's kernels where Debian's OpenBLAS does not know the CPU (run by setup.sh).

Debian 12's OpenBLAS (0.3.21) chooses its kernels at load time from the CPU's model number.
A processor newer than it (an Intel Xeon of model 207, "Emerald Rapids", is one) is not in
its table, and it falls back to its generic "Prescott" kernels (SSE3): on such a machine a
2000 x 2000 matrix product took 2.9 s instead of 0.59 s and an LU 1.1 s instead of 0.41 s,
and the main job's dense stability checks slowed down in proportion. OpenBLAS's own
environment variable ``OPENBLAS_CORETYPE`` overrides the choice; it must be set before the
library loads, that is before numpy is imported.

``python scripts/openblas_core.py VENV`` (setup.sh runs it with the venv's interpreter):

1. asks the venv's numpy which kernels OpenBLAS picks by itself (``OPENBLAS_VERBOSE=2``);
2. if that is a generic fallback and the CPU has the instructions of a better kernel
   (AVX-512 F/DQ/CD/BW/VL: SkylakeX; AVX2 and FMA: Haswell; AVX: SandyBridge), writes a
   start-up hook into the venv (``upd_openblas.pth`` and ``upd_openblas.py`` in its
   site-packages) that sets ``OPENBLAS_CORETYPE`` for every process of the venv (``upd``,
   pytest, the MPI ranks, the benchmarks); otherwise removes any such hook.

The hook applies only on a CPU with the same vendor, family, model and flags as the one it
was chosen on (a venv or image moved to another machine runs setup again, or falls back to
OpenBLAS's own choice), and never overrides an ``OPENBLAS_CORETYPE`` set by the user.
Prints one line saying what it found and did.
"""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
import sysconfig
from pathlib import Path

# OpenBLAS's generic kernels: what its dynamic dispatch falls back to for a model it does not
# know (x86-64 names as OPENBLAS_VERBOSE prints them).
GENERIC = {
    "prescott",
    "core2",
    "penryn",
    "dunnington",
    "nehalem",
    "atom",
    "katmai",
    "coppermine",
    "northwood",
    "banias",
    "opteron",
    "opteron(sse3)",
    "barcelona",
    "athlon",
    "unknown",
}
# better kernels, best first, with the CPU flags each needs
KERNELS = (
    ("SkylakeX", ("avx512f", "avx512dq", "avx512cd", "avx512bw", "avx512vl", "avx2", "fma")),
    ("Haswell", ("avx2", "fma")),
    ("SandyBridge", ("avx",)),
)
HOOK = "upd_openblas"
TEMPLATE = Path(__file__).with_name(f"{HOOK}.py")


def choose(detected: str | None, flags: set[str]) -> str | None:
    """The kernel to force, or None: only when OpenBLAS fell back to a generic kernel and the
    CPU has the instructions of a better one."""
    if detected is None or detected.strip().lower() not in GENERIC:
        return None
    for core, need in KERNELS:
        if all(f in flags for f in need):
            return core
    return None


def kernels_in_use(python: str, env: dict[str, str]) -> str | None:
    """The kernels OpenBLAS runs in ``python``'s numpy started with ``env`` (None: not
    OpenBLAS, or it did not say)."""
    out = subprocess.run(
        [python, "-c", "import numpy"],
        env={**env, "OPENBLAS_VERBOSE": "2"},
        capture_output=True,
        text=True,
        timeout=120,
    )
    m = re.search(r"^Core:\s*(\S.*)$", out.stdout + out.stderr, re.M)
    return m[1].strip() if m else None


def detected_core(python: str) -> str | None:
    """The kernels OpenBLAS picks by itself in ``python``'s numpy: no OPENBLAS_CORETYPE, the
    hook kept out."""
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_CORETYPE"}
    return kernels_in_use(python, {**env, "UPD_OPENBLAS_PROBE": "1"})


def template():
    """The hook's module as this checkout has it (not a copy already installed and imported)."""
    spec = importlib.util.spec_from_file_location(f"{HOOK}_template", TEMPLATE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def install(site_dir: Path, core: str, signature: str) -> None:
    """The hook, with its kernel and CPU signature, into ``site_dir``."""
    text = TEMPLATE.read_text()
    text = text.replace("\nCORE = None\n", f"\nCORE = {core!r}\n", 1)
    text = text.replace("\nSIGNATURE = None\n", f"\nSIGNATURE = {signature!r}\n", 1)
    (site_dir / f"{HOOK}.py").write_text(text)
    (site_dir / f"{HOOK}.pth").write_text(f"import {HOOK}\n")


def main(argv: list[str]) -> int:
    if len(argv) != 1:
        print("usage: openblas_core.py VENV", file=sys.stderr)
        return 2
    venv = Path(argv[0])
    site_dir = Path(sysconfig.get_paths()["purelib"])
    if Path(sys.prefix).resolve() != venv.resolve():
        print(f"setup: openblas_core: run it with {venv}/bin/python", file=sys.stderr)
        return 2
    try:
        signature, flags = template().cpu()
    except OSError:
        print("setup: OpenBLAS kernels left to OpenBLAS (no /proc/cpuinfo)", file=sys.stderr)
        return 0
    detected = detected_core(sys.executable)
    core = choose(detected, flags)
    if core is None:
        for suffix in (".pth", ".py"):
            (site_dir / f"{HOOK}{suffix}").unlink(missing_ok=True)
        print(
            f"setup: OpenBLAS kernels: {detected or 'not reported'} (its own choice)",
            file=sys.stderr,
        )
        return 0
    install(site_dir, core, signature)
    print(
        f"setup: OpenBLAS does not know this CPU ({signature.rsplit(' ', 1)[0]}) and picks "
        f"its generic {detected} kernels; {HOOK}.pth sets OPENBLAS_CORETYPE={core}",
        file=sys.stderr,
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))

"""OpenBLAS's kernels: setup's start-up hook picks real ones where Debian's OpenBLAS would fall
back to its generic kernels (scripts/openblas_core.py, scripts/upd_openblas.py)."""

import importlib.util
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _load(name):
    spec = importlib.util.spec_from_file_location(f"_{name}", ROOT / "scripts" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


core = _load("openblas_core")
AVX512 = {"sse3", "avx", "avx2", "fma", "avx512f", "avx512dq", "avx512cd", "avx512bw", "avx512vl"}


def test_choose_only_overrides_a_generic_fallback():
    # the case met on an Emerald Rapids Xeon (model 207) with Debian 12's OpenBLAS 0.3.21
    assert core.choose("Prescott", AVX512) == "SkylakeX"
    assert core.choose("Core2", {"avx", "avx2", "fma"}) == "Haswell"
    assert core.choose("Nehalem", {"avx"}) == "SandyBridge"
    # no better kernel than the generic one for this CPU: leave it
    assert core.choose("Prescott", {"sse3", "ssse3"}) is None
    # OpenBLAS knew the CPU (its own choice stands, even below the flags' best)
    assert core.choose("Haswell", AVX512) is None
    assert core.choose("SkylakeX", AVX512) is None
    assert core.choose("Zen", AVX512) is None
    # not OpenBLAS, or it said nothing
    assert core.choose(None, AVX512) is None


def _hook_env(tmp_path, signature, **env):
    """OPENBLAS_CORETYPE as a fresh interpreter sees it with the hook installed for
    ``signature`` (in ``tmp_path``, read as a site folder so that its .pth runs)."""
    core.install(tmp_path, "SkylakeX", signature)
    code = (
        "import site, sys, os; site.addsitedir(sys.argv[1]); "
        "print(os.environ.get('OPENBLAS_CORETYPE', '-'))"
    )
    base = {
        k: v for k, v in os.environ.items() if k not in ("OPENBLAS_CORETYPE", "UPD_OPENBLAS_PROBE")
    }
    out = subprocess.run(
        [sys.executable, "-S", "-c", code, str(tmp_path)],
        env={**base, **env},
        capture_output=True,
        text=True,
        check=True,
    )
    return out.stdout.strip()


def test_hook_applies_on_its_cpu_only_and_never_over_the_user(tmp_path):
    here = core.template().cpu()[0]
    assert _hook_env(tmp_path, here) == "SkylakeX"
    # another machine (the venv or image moved): OpenBLAS's own choice
    assert _hook_env(tmp_path, "GenuineIntel 6 1 00000000") == "-"
    # the user's setting wins, and the probe sees OpenBLAS's own choice
    assert _hook_env(tmp_path, here, OPENBLAS_CORETYPE="Haswell") == "Haswell"
    assert _hook_env(tmp_path, here, UPD_OPENBLAS_PROBE="1") == "-"


def test_this_stack_runs_openblas_on_real_kernels():
    """What setup left behind: numpy's OpenBLAS does not run its generic kernels on a CPU
    that has AVX2 and FMA (on such a CPU they were 3-7 times slower on dense algebra)."""
    flags = core.template().cpu()[1]
    env = {k: v for k, v in os.environ.items() if k != "UPD_OPENBLAS_PROBE"}
    kernels = core.kernels_in_use(sys.executable, env)
    assert kernels, "numpy did not load OpenBLAS (it printed no 'Core:' line)"
    if {"avx2", "fma"} <= flags:
        assert kernels.lower() not in core.GENERIC, kernels

"""OpenBLAS kernels for a CPU that Debian's OpenBLAS does not know (a start-up hook).

scripts/openblas_core.py (run by setup.sh) copies this file into the venv's site-packages,
with CORE and SIGNATURE filled in, beside ``upd_openblas.pth``, which imports it when any
interpreter of the venv starts. It then sets OPENBLAS_CORETYPE=CORE before numpy loads
OpenBLAS, on a CPU of this SIGNATURE only (vendor, family, model, a digest of the flags),
and never where OPENBLAS_CORETYPE is set already or UPD_OPENBLAS_PROBE is set (the probe
that asks OpenBLAS for its own choice). As it stands here (CORE None) it does nothing.
Standard library only: it runs before anything else is importable.
"""

import os
import zlib

CORE = None
SIGNATURE = None


def cpu() -> tuple[str, set[str]]:
    """This CPU's signature (vendor, family, model, a digest of its flags) and its flags."""
    vendor = family = model = flags = ""
    with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as f:
        for line in f:
            key, _, value = line.partition(":")
            key, value = key.strip(), value.strip()
            if key == "vendor_id" and not vendor:
                vendor = value
            elif key == "cpu family" and not family:
                family = value
            elif key == "model" and not model:
                model = value
            elif key == "flags":
                flags = value
                break
    digest = f"{zlib.crc32(flags.encode()):08x}"
    return " ".join((vendor, family, model, digest)), set(flags.split())


def apply() -> None:
    if not CORE or "OPENBLAS_CORETYPE" in os.environ or "UPD_OPENBLAS_PROBE" in os.environ:
        return
    try:
        if cpu()[0] == SIGNATURE:
            os.environ["OPENBLAS_CORETYPE"] = CORE
    except OSError:
        pass


apply()

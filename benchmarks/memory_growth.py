"""Does a process grow with every model it builds? (the pad study's processes reached 13.5 GB)

Builds N distinct coarse models of the paper-like rig's cone in one process (the global
mesh size stepped so that each is new), stage by stage, and prints the resident memory
after the mesh (gmsh) and after each body's Craig-Bampton reduction (dolfinx, SLEPc),
with Python's garbage collected first. A stage whose memory steps up by a similar amount
at every model and never comes back holds on to something it should have freed.

    python benchmarks/memory_growth.py            # 6 models at 14-11.5 mm (a few minutes)
    python benchmarks/memory_growth.py --n 10

Scratch folder: results/memory_growth/ (emptied first).
"""

from __future__ import annotations

import argparse
import gc
import os
import shutil
import sys
import time
from pathlib import Path

for _k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
    os.environ.setdefault(_k, "1")
os.environ["UPD_WORKERS"] = "1"  # everything in this process: its memory is the point

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
OUT = ROOT / "results" / "memory_growth"


def rss_gb(trim: bool) -> float:
    """This process's resident set (GB) after a full garbage collection (and, with
    ``trim``, glibc's ``malloc_trim(0)``)."""
    gc.collect()
    if trim:
        import ctypes

        ctypes.CDLL("libc.so.6").malloc_trim(0)
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1e6
    return float("nan")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=6, help="number of models (default 6)")
    ap.add_argument(
        "--trim",
        action="store_true",
        help="return the C heap's free memory to the system after each stage (glibc "
        "malloc_trim): growth that this removes is fragmentation, not retention",
    )
    a = ap.parse_args()
    if not 1 <= a.n <= 20:
        ap.error(f"--n: {a.n} models; allowed 1 to 20 (the mesh size steps down 0.5 mm a model)")
    from workbench.fe.reduce import reduce_body
    from workbench.geometry import build_geometry

    if OUT.exists():
        shutil.rmtree(OUT)
    geometry = ROOT / "geometry" / "paper_rig.toml"
    coarse = {"rig": {"mesh": {"contact_size_mm": 3.0}}}
    print(f"start: {rss_gb(a.trim):.2f} GB", flush=True)
    first = None
    for i in range(a.n):
        size = 14.0 - 0.5 * i
        t0 = time.perf_counter()
        geom = build_geometry("cone", OUT / f"g{i}", geometry_file=geometry, size_mm=size,
                              overrides=coarse)  # fmt: skip
        after_mesh = rss_gb(a.trim)
        steps = []
        for body in ("rig", "damper"):
            rm = reduce_body(geom, body, n_modes=12, rigid=False, cache_dir=OUT / "fe")
            del rm
            steps.append(rss_gb(a.trim))
        del geom
        end = rss_gb(a.trim)
        first = first if first is not None else end
        took = time.perf_counter() - t0
        print(f"model {i + 1} ({size:g} mm, {took:.0f} s): mesh {after_mesh:.2f} GB, "
              f"rig {steps[0]:.2f} GB, damper {steps[1]:.2f} GB, after {end:.2f} GB "
              f"(+{end - first:.2f} GB since the first)", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()

"""A copy of a geometry file with ``[rig.mesh] mirror`` set: the benchmarks that compare
whole and mirror-image meshes (`mirror_fidelity.py`, `remesh_noise.py`) run both from one
file, whatever that file itself sets."""

from __future__ import annotations

import re
from pathlib import Path


def with_mirror(src: Path, mirror: bool, out: Path, note: str) -> Path:
    """Write ``src`` with ``mirror = true|false`` as the first key of its ``[rig.mesh]``
    table (added if missing; any ``mirror`` line of the file dropped) to ``out``."""
    text = re.sub(r"(?m)^mirror\s*=.*\n", "", src.read_text())
    flag = "true" if mirror else "false"
    if "\n[rig.mesh]" in text:
        table = r"\n\[rig\.mesh\][^\n]*\n"
        text = re.sub(table, lambda m: m.group(0) + f"mirror = {flag}\n", text, count=1)
    else:
        text += f"\n[rig.mesh]\nmirror = {flag}\n"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(f"# {src.name} with mirror = {flag} ({note})\n" + text)
    return out

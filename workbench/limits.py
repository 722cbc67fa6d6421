"""Limits that a real rig or a double-precision solve cannot leave, each with its reason.

The study options, the model files of ``upd frf``/``upd nlmodes`` and the
command-line options take their ranges from here, so that the help, the
checks and the messages say the same. A *physical* limit (a force, a
contact stiffness, a band) can be passed with ``allow-extreme`` where a user
may truly need it (a numerical experiment); a *numerical* limit (matrix
entries, memory) cannot.

:func:`check_memory` refuses a computation whose arrays would not fit in
the memory available now, before they are allocated.
"""

from __future__ import annotations

from pathlib import Path

from .errors import InputError

# -- physical ranges of the study options (SI; soft: allow-extreme passes them) -----------
FORCE_MAX_N = 1.0e4
FORCE_WHY = (
    "a shaker on a blade rig gives at most a few kN; beyond 10 kN the blade is far past yield"
)
CF_MAX_N = 1.0e6
CF_WHY = "1 MN is a 1 kg damper at 100 000 g, beyond any engine"
K_LINE_N_PER_M2 = (1.0e6, 1.0e14)
K_LINE_WHY = (
    "a steel line contact is about 1e11 N/m per m; above 1e14 the contact is stiffer than "
    "the blades and the stuck system loses its digits, below 1e6 the damper floats"
)
K_FACE_N_PER_M3 = (1.0e8, 1.0e16)
K_FACE_WHY = (
    "a steel face contact is about 1e12-1e13 N/m per m^2; above 1e16 the contact is "
    "stiffer than the blades and the stuck system loses its digits, below 1e8 the damper "
    "floats"
)
BAND_MAX_HZ = 1.0e5
BAND_WHY = "a reduced blade model with tens of modes means nothing above 100 kHz"
BAND_RATIO_MAX = 10.0
BAND_RATIO_WHY = (
    "one family's resonance lies in a band much narrower than a decade; a wider band "
    "walks the continuation over other modes for minutes"
)
UQ_THRESHOLD_MAX_MM = 100.0
UQ_THRESHOLD_WHY = "a blade tip moving 100 mm has broken"
EXTREME_HINT = "allow-extreme = true (--allow-extreme) accepts it"

# -- model files of upd frf / upd nlmodes (any unit system: ratios, not magnitudes) -------
MU_MAX = 2.0
MU_WHY = "no dry contact of engineering materials has a friction coefficient above 2"
FRF_BAND_RATIO_MAX = 1.0e3
FRF_BAND_WHY = (
    "over more than three decades the continuation walks every mode in between for "
    "minutes; split the band around the resonances"
)
LEVEL_OVER_SLIP_MAX = 1.0e4
LEVEL_WHY = (
    "beyond 10^4 times the largest slip force mu N0 the friction forces are lost in the "
    "linear response: the curve is the sliding limit's"
)
CONTACT_STIFFNESS_RATIO_MAX = 1.0e9
CONTACT_STIFFNESS_WHY = (
    "a contact spring more than 10^9 times the model's stiffest diagonal term makes the "
    "stuck system singular in double precision"
)

# -- numerical limits (no override) ---------------------------------------------------------
MAX_HARMONIC = 256
MAX_NT = 1 << 16
NT_WHY = "2^16 samples per period resolve harmonic 256 with a margin of 128"
ENTRY_MAX = 1.0e100
ENTRY_MIN = 1.0e-100
ENTRY_WHY = "products of such numbers overflow or underflow double precision; rescale the units"


def available_memory() -> int | None:
    """Bytes of memory available now (MemAvailable, or the cgroup's limit), None if unknown."""
    avail = None
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                avail = int(line.split()[1]) * 1024
                break
    except (OSError, ValueError, IndexError):
        avail = None
    try:  # a container's own limit (cgroup v2)
        limit = Path("/sys/fs/cgroup/memory.max").read_text().strip()
        used = int(Path("/sys/fs/cgroup/memory.current").read_text().strip())
        if limit != "max":
            free = max(int(limit) - used, 0)
            avail = free if avail is None else min(avail, free)
    except (OSError, ValueError):
        pass
    return avail


def _size(n: float) -> str:
    for unit, f in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6)):
        if n >= f:
            return f"{n / f:.3g} {unit}"
    return f"{n / 1e3:.3g} kB"


def check_memory(need_bytes: float, param: str, value: object, what: str) -> None:
    """Refuse ``value`` of ``param`` when ``what`` needs more memory than is available.

    ``need_bytes``: an estimate of the arrays the computation holds at once.
    Called before they are allocated, so a bad input costs no swap storm and
    no MemoryError deep inside numpy.
    """
    avail = available_memory()
    if avail is None or need_bytes <= avail:
        return
    raise InputError(
        param,
        value,
        f"a size whose arrays fit in memory ({_size(avail)} available)",
        f"{what} would need about {_size(need_bytes)}",
    )

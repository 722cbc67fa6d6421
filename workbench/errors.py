"""Errors that the ``upd`` command reports as one line.

Library code raises :class:`InputError` for anything a user can fix in
their input (a parameter out of range, an unknown key, a file that does not
exist) and :class:`SolveError` when a computation fails. The CLI turns the
first into exit code 2 and the second into exit code 3, each with a single
line on stderr and no traceback (``--debug`` shows it).
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable


class WorkbenchError(Exception):
    """Base class of the errors the CLI reports without a traceback."""

    exit_code = 1


class InputError(WorkbenchError, ValueError):
    """A parameter has a value outside what is allowed.

    >>> str(InputError("beta_deg", 95.0, "0 < beta_deg < 90"))
    'beta_deg = 95.0 is not allowed: expected 0 < beta_deg < 90'
    """

    exit_code = 2

    def __init__(self, param: str, value: object, allowed: str, why: str = ""):
        self.param, self.value, self.allowed, self.why = param, value, allowed, why
        msg = f"{param} = {value!r} is not allowed: expected {allowed}"
        if why:
            msg += f" ({why})"
        super().__init__(msg)


class SolveError(WorkbenchError, RuntimeError):
    """A solve failed; ``partial`` carries what was computed before it.

    ``summary``: the command's JSON summary of what was done; the CLI still
    prints it (before the error line and exit code 3).
    """

    exit_code = 3

    def __init__(self, message: str, partial: object = None, summary: dict | None = None):
        self.partial = partial
        self.summary = summary
        super().__init__(message)


def run_on_root(comm, fn, what: str):
    """``fn()`` on rank 0 of ``comm``: its result there, None on the other ranks.

    An error on rank 0 is raised on every rank (an InputError as itself, any
    other as a SolveError naming ``what``): a rank that raised alone would
    leave the others waiting in their next collective. Collective.
    """
    failure: tuple | None = None
    out = None
    if comm.rank == 0:
        try:
            out = fn()
        except InputError as e:
            failure = ("input", e.param, e.value, e.allowed, e.why)
        except WorkbenchError as e:
            failure = ("solve", str(e))
        except Exception as e:  # noqa: BLE001 - re-raised below on every rank
            failure = ("solve", f"{what} failed on rank 0: {type(e).__name__}: {e}")
    failure = comm.bcast(failure, root=0)
    if failure is not None:
        if failure[0] == "input":
            raise InputError(*failure[1:])
        raise SolveError(failure[1])
    return out


def check_range(
    param: str,
    value: float,
    lo: float | None = None,
    hi: float | None = None,
    *,
    lo_open: bool = False,
    hi_open: bool = False,
    unit: str = "",
) -> float:
    """Return ``float(value)`` if it lies in the interval, else raise InputError.

    ``lo_open``/``hi_open`` exclude the bound itself. Non-numbers and NaN are
    refused with the same one-line message.
    """
    u = f" {unit}" if unit else ""
    left = "" if lo is None else f"{lo:g}{u} {'<' if lo_open else '<='} "
    right = "" if hi is None else f" {'<' if hi_open else '<='} {hi:g}{u}"
    allowed = f"{left}{param}{right}" if (left or right) else "a number"
    if isinstance(value, bool):
        raise InputError(param, value, allowed, "not a number")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(param, value, allowed, "not a number") from None
    if v != v or v in (float("inf"), float("-inf")):
        raise InputError(param, value, allowed, "not a finite number")
    if lo is not None and (v < lo or (lo_open and v == lo)):
        raise InputError(param, value, allowed)
    if hi is not None and (v > hi or (hi_open and v == hi)):
        raise InputError(param, value, allowed)
    return v


def check_int(param: str, value: object, lo: int | None = None, hi: int | None = None) -> int:
    """Return ``int(value)`` if it is a whole number within [lo, hi], else raise InputError.

    The one rule for every whole-number input (command line, study and model
    files): ``12``, ``12.0``, ``"12"`` and ``"1e3"`` are whole numbers; ``1.5``,
    NaN, infinity, text and booleans are refused with the same one-line message.
    """
    allowed = (
        f"a whole number {'' if lo is None else f'{lo} <= '}{param}"
        f"{'' if hi is None else f' <= {hi}'}"
    )
    if isinstance(value, bool):
        raise InputError(param, value, allowed)
    if isinstance(value, int):
        f: float | int = value  # exact, however large (a float would round it)
    else:
        try:
            f = float(value.strip() if isinstance(value, str) else value)  # 12, 12.0, "12", "1e3"
        except (TypeError, ValueError):
            raise InputError(param, value, allowed, "not a number") from None
    if f != f or f in (float("inf"), float("-inf")):
        raise InputError(param, value, allowed, "not a finite number")
    if f != int(f):
        raise InputError(param, value, allowed, "not a whole number")
    v = int(f)
    if (lo is not None and v < lo) or (hi is not None and v > hi):
        raise InputError(param, value, allowed)
    return v


def check_choice(param: str, value: object, choices: Iterable[str]) -> str:
    """Return ``value`` if it is one of ``choices``; suggest the closest otherwise."""
    choices = list(choices)
    if value in choices:
        return value  # type: ignore[return-value]
    raise InputError(param, value, "one of " + ", ".join(choices), did_you_mean(value, choices))


def did_you_mean(word: object, candidates: Iterable[str]) -> str:
    """A hint naming the closest candidate, or an empty string."""
    close = difflib.get_close_matches(str(word), list(candidates), n=1, cutoff=0.5)
    return f"did you mean {close[0]!r}?" if close else ""

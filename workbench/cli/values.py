"""The numbers typed on the command line: one rule per kind, the range in the help.

An option that takes a number or a list of numbers is declared with
:func:`add_value` and a :class:`Value` (kind, range, unit, reason). Its help
ends with the range, so ``upd <command> --help`` states what is allowed,
and :func:`check_values` converts and checks every such option of the
command before it runs (``workbench.cli.main``), so a bad value costs no
work. Whole numbers go through :func:`workbench.errors.check_int`, the rule
of every whole-number input (study files and model files too): NaN,
infinity, ``1.5`` and text are one clear line and exit code 2.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from typing import Any

from ..errors import InputError, check_int, check_range


@dataclass(frozen=True)
class Value:
    """What an option's value may be.

    ``kind``: "int", "float", "ints" or "floats" (comma-separated);
    ``count``: a list of exactly this many values; ``rising``: each value
    above the one before; ``ratio``: the largest at most this times the
    smallest; ``why``: the reason for the range, said when it is refused;
    ``name``: the parameter the messages name, where the library names it
    so too (``points`` of ``upd analytic``); the flag by default.
    """

    kind: str
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    unit: str = ""
    count: int | None = None
    rising: bool = False
    ratio: float | None = None
    why: str = ""
    name: str = ""  # how the messages name it (default: the flag)

    def describe(self, metavar: str = "X") -> str:
        """The range in words, for the help: 'a whole number 1 <= N <= 200'."""
        whole = self.kind in ("int", "ints")
        u = f" {self.unit}" if self.unit else ""
        lo = "" if self.lo is None else f"{self.lo:g} {'<' if self.lo_open else '<='} "
        hi = "" if self.hi is None else f" <= {self.hi:g}"
        if self.kind in ("int", "float"):
            what = "a whole number" if whole else "a number"
            return f"{what} {lo}{metavar}{hi}{u}" if lo or hi else what + u
        what = "whole numbers" if whole else "numbers"
        what = f"{self.count} {what}" if self.count else f"comma-separated {what}"
        each = []
        if self.lo is not None:
            each.append(f"{'>' if self.lo_open else '>='} {self.lo:g}")
        if self.hi is not None:
            each.append(f"<= {self.hi:g}")
        text = what + (f", each {' and '.join(each)}{u}" if each else u)
        if self.rising:
            text += ", rising"
        if self.ratio:
            text += f", the last at most {self.ratio:g} x the first"
        return text

    def check(self, name: str, raw: Any) -> Any:
        """``raw`` (text from the command line) converted and checked, else InputError."""
        if self.kind in ("int", "float"):
            return self._one(name, raw)
        text = str(raw)
        items = [t.strip() for t in text.split(",")]
        if not text.strip() or any(t == "" for t in items):
            raise InputError(name, text, self.describe(), "an empty value in the list")
        if self.count is not None and len(items) != self.count:
            raise InputError(
                name, text, self.describe(), f"{len(items)} value{'s' * (len(items) != 1)} given"
            )
        vals = [
            self._one(f"{name}[{i}]" if len(items) > 1 else name, t) for i, t in enumerate(items)
        ]
        if self.rising and any(b <= a for a, b in zip(vals, vals[1:], strict=False)):
            raise InputError(name, text, self.describe(), "each value must be above the one before")
        if self.ratio and min(vals) > 0 and max(vals) / min(vals) > self.ratio:
            raise InputError(
                name,
                text,
                self.describe(),
                self.why or f"largest / smallest = {max(vals) / min(vals):.3g}",
            )
        return vals

    def _one(self, name: str, text: Any) -> Any:
        whole = self.kind in ("int", "ints")
        lo, hi = self.lo, self.hi
        try:  # a number is shown as a number ("n = 0"), anything else as typed
            f = float(text)
            if f == f and abs(f) != float("inf"):
                text = int(f) if whole and f == int(f) else f
        except (TypeError, ValueError):
            pass
        try:
            if whole:
                return check_int(
                    name, text, None if lo is None else int(lo), None if hi is None else int(hi)
                )
            return check_range(name, text, lo, hi, lo_open=self.lo_open, unit=self.unit)
        except InputError as e:
            if self.why and not e.why:
                raise InputError(e.param, e.value, e.allowed, self.why) from None
            raise


def add_value(
    parser: argparse.ArgumentParser | Any,
    flag: str,
    value: Value,
    help: str,
    *,
    metavar: str,
    default: Any = None,
) -> argparse.Action:
    """``parser.add_argument(flag)`` with the range at the end of its help; the value is
    checked by :func:`check_values` before the command runs."""
    shown = "" if default is None else f" [default: {default}]"
    action = parser.add_argument(
        flag,
        metavar=metavar,
        default=default,
        help=f"{help}{shown}; {value.describe(metavar)}",
    )
    action.value = value  # type: ignore[attr-defined]
    return action


def value_actions(parser: argparse.ArgumentParser) -> list[argparse.Action]:
    """The options of ``parser`` declared with :func:`add_value`."""
    return [a for a in parser._actions if hasattr(a, "value")]  # noqa: SLF001


def check_values(parser: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """Convert and check every :func:`add_value` option (given or default) in place."""
    for a in value_actions(parser):
        raw = getattr(args, a.dest, None)
        if raw is None:
            continue
        v = a.value  # type: ignore[attr-defined]
        setattr(args, a.dest, v.check(v.name or a.option_strings[-1], raw))

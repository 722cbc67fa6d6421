"""Entry point of the ``upd`` command.

Every sub-command lives in a module ``workbench.cli.cmd_<name>`` with::

    HELP = "one line for `upd --help`"
    DESCRIPTION = "a paragraph for `upd <name> --help`"   (optional)
    def add_arguments(parser: argparse.ArgumentParser) -> None: ...
    def run(args: argparse.Namespace, ctx: Context) -> dict: ...

``run`` returns a JSON-able summary. With ``--json`` it is printed on stdout
(and nothing else is); otherwise a short human-readable form is. Command
modules import heavy libraries (dolfinx, pyvista) inside ``run`` only, so
``upd --help`` stays fast.

Errors: :class:`~workbench.errors.InputError` -> one line, exit 2;
:class:`~workbench.errors.SolveError` -> one line, exit 3; Ctrl-C -> exit
130; anything else -> one line naming the exception, exit 1. ``--debug``
adds the traceback.
"""

from __future__ import annotations

import argparse
import importlib
import json
import logging
import os
import re
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .. import __version__
from ..errors import InputError, WorkbenchError
from ..io import rescue_folder, to_jsonable, unwritable, utf8_name
from .values import check_values

COMMANDS = [
    "analytic",
    "mesh",
    "modes",
    "reduce",
    "screen",
    "frf",
    "nlmodes",
    "study",
    "report",
    "disk",
]

log = logging.getLogger("workbench.cli")


@dataclass
class Context:
    """What every command receives besides its own options."""

    out: Path | None
    json: bool
    debug: bool
    timings: dict[str, float] = field(default_factory=dict)
    created: list[Path] = field(default_factory=list)  # folders out_dir made, outermost first
    command: str = "upd"
    folder: Path | None = None  # where the results go (out_dir's, or the rescue folder)
    rescued: str = ""  # why the results went to a rescue folder, if they did

    def out_dir(self, default: str) -> Path:
        """The output folder (``--out`` or ``default``), created and proven writable.

        Called before any work: a path that cannot be a folder (an existing
        file, ``/proc/x``, ``/sys/kernel``, a read-only file system, no
        permission) is an InputError naming ``--out``, so no computed work
        is lost to it.
        """
        p = self.out if self.out is not None else Path(default)
        what = "--out" if self.out is not None else "output folder"
        shown = utf8_name(str(p.absolute()))
        if shown is not None:
            raise InputError(
                what,
                _Shown(shown),
                "a folder whose path is UTF-8",
                "rename the folder, or work from a folder whose name is UTF-8",
            )
        if p.exists() and not p.is_dir():
            raise InputError(what, str(p), "a folder", "it is an existing file")
        new = [q for q in (p, *p.parents) if not q.exists()][::-1]
        try:
            p.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise InputError(
                what, str(p), "a folder that can be created", e.strerror or type(e).__name__
            ) from None
        self.created += new
        why = unwritable(p)
        if why is not None:
            raise InputError(what, str(p), "a folder you can write to", why)
        self.folder = p
        return p

    def write(self, fn: Callable[[Path], Any]) -> Any:
        """``fn(folder)``: write results into the output folder; if that fails once the work
        is done (the disk filled, the folder went away), write them into a rescue folder
        instead, say where in a warning and in the summary (``out``, ``out_note``)."""
        assert self.folder is not None, "out_dir() first"
        try:
            return fn(self.folder)
        except OSError as e:
            if self.rescued:
                raise
            self.rescued = f"could not write to {self.folder} ({e.strerror or e})"
            self.folder = rescue_folder(self.command)
            log.warning("%s; the results are written to %s instead", self.rescued, self.folder)
            return fn(self.folder)

    def note_rescue(self, summary: dict[str, Any]) -> dict[str, Any]:
        """``summary`` with ``out`` the folder the results are in, and why if rescued."""
        if self.folder is not None:
            summary["out"] = str(self.folder)
        if self.rescued:
            summary["out_note"] = f"{self.rescued}; the results are in {self.folder}"
        return summary

    def remove_empty_created(self) -> None:
        """Remove the folders :meth:`out_dir` made if nothing but empty folders is in them
        (rejected input leaves no empty output folder behind)."""
        if not self.created:
            return
        for root, _, _ in sorted(os.walk(self.created[-1]), key=lambda t: -len(t[0])):
            try:
                Path(root).rmdir()
            except OSError:
                return
        for q in reversed(self.created[:-1]):
            try:
                q.rmdir()
            except OSError:
                return


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors and exit code 2."""

    def error(self, message: str) -> None:  # type: ignore[override]
        sys.stderr.write(f"{self.prog}: error: {message} (see {self.prog} --help)\n")
        sys.exit(2)


def _common(suppress: bool) -> argparse.ArgumentParser:
    d = (lambda v: argparse.SUPPRESS) if suppress else (lambda v: v)
    p = argparse.ArgumentParser(add_help=False)
    g = p.add_argument_group("common options")
    g.add_argument(
        "--json",
        action="store_true",
        default=d(False),
        help="print a machine-readable summary on stdout (logs go to stderr)",
    )
    g.add_argument(
        "--out",
        metavar="DIR",
        default=d(None),
        help="folder for the files this command writes (default: a folder under ./results "
        "named after the command and its damper or study, e.g. results/modes_cone; created "
        "if missing, and printed as out: in the summary); a non-empty UTF-8 path of a "
        "folder you can write to, checked before any work",
    )
    g.add_argument("-v", "--verbose", action="count", default=d(0), help="more log messages")
    g.add_argument(
        "-q",
        "--quiet",
        action="count",
        default=d(0),
        help="only warnings and errors; no progress bars",
    )
    g.add_argument(
        "--debug", action="store_true", default=d(False), help="show the traceback of an error"
    )
    return p


def add_geometry_options(parser: argparse.ArgumentParser, contact_help: str | None = None) -> None:
    """--size and --geometry (and --contact-file with its help, if given) of the FE commands."""
    from ..geometry.params import MAX_SIZE_MM

    parser.add_argument(
        "--size",
        type=num,
        metavar="MM",
        default=None,
        help="global element size of the rig, mm (default: [rig.mesh] size_mm); "
        f"0 < MM <= {MAX_SIZE_MM:g}, and coarse enough for at most a few million "
        "tetrahedra",
    )
    parser.add_argument(
        "--geometry",
        type=Path,
        metavar="FILE",
        default=None,
        help="TOML file overriding tables of the default geometry files",
    )
    if contact_help is not None:
        parser.add_argument(
            "--contact-file", type=Path, metavar="FILE", default=None, help=contact_help
        )


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="upd",
        description="Under-platform damper workbench: analytic cone kinematics, gmsh meshes, "
        "dolfinx/SLEPc Craig-Bampton models, multi-harmonic balance with 3-D friction "
        "contact, damper studies and reports.",
        parents=[_common(False)],
        epilog="Run `upd <command> --help` for the options of a command.",
    )
    parser.add_argument("--version", action="version", version=f"upd-workbench {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="<command>", parser_class=_Parser)
    for name in COMMANDS:
        try:
            mod = importlib.import_module(f"workbench.cli.cmd_{name}")
        except ModuleNotFoundError as e:
            if e.name == f"workbench.cli.cmd_{name}":
                continue  # not built yet
            raise
        p = sub.add_parser(
            name,
            help=mod.HELP,
            description=getattr(mod, "DESCRIPTION", mod.HELP),
            parents=[_common(True)],
            formatter_class=argparse.RawDescriptionHelpFormatter,
        )
        mod.add_arguments(p)
        p.set_defaults(_run=mod.run, _parser=p)
    return parser


def _human(summary: dict[str, Any], indent: str = "") -> str:
    lines = []
    for k, v in summary.items():
        if isinstance(v, dict):
            lines.append(f"{indent}{k}:")
            lines.append(_human(v, indent + "  "))
        elif isinstance(v, list) and v and isinstance(v[0], dict):
            lines.append(f"{indent}{k}: ({len(v)} rows)")
            for row in v:
                lines.append(indent + "  - " + ", ".join(f"{a}={_fmt(b)}" for a, b in row.items()))
        else:
            lines.append(f"{indent}{k}: {_fmt(v)}")
    return "\n".join(lines)


def _fmt(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, list) and len(v) > 12:
        return "[" + ", ".join(_fmt(x) for x in v[:12]) + f", ... ({len(v)} values)]"
    if isinstance(v, list):
        return "[" + ", ".join(_fmt(x) for x in v) + "]"
    return str(v)


_NEGATIVE = re.compile(r"^-(\d|\.\d|inf|nan)", re.IGNORECASE)


def join_negative_values(parser: argparse.ArgumentParser, argv: list[str]) -> list[str]:
    """``--harmonics -1,1`` -> ``--harmonics=-1,1`` for the options that take a value.

    argparse takes a value starting with ``-`` that is not a plain negative
    number (``-1,1``, ``-1e3``) for an option and reports "expected one
    argument"; joined, the value reaches the check that names the option
    and what is allowed.
    """
    takes_value: set[str] = set()
    parsers = [parser]
    for a in parser._actions:  # noqa: SLF001 - argparse has no public walk of sub-parsers
        if isinstance(a, argparse._SubParsersAction):  # noqa: SLF001
            parsers += list(a.choices.values())
    for p in parsers:
        for opt, a in p._option_string_actions.items():  # noqa: SLF001
            if opt.startswith("--") and a.nargs != 0:
                takes_value.add(opt)
    out: list[str] = []
    i = 0
    while i < len(argv):
        tok = argv[i]
        if tok in takes_value and i + 1 < len(argv) and _NEGATIVE.match(argv[i + 1]):
            out.append(f"{tok}={argv[i + 1]}")
            i += 2
            continue
        out.append(tok)
        i += 1
    return out


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    argv = list(sys.argv[1:] if argv is None else argv)
    args = parser.parse_args(join_negative_values(parser, argv))
    if not getattr(args, "_run", None):
        parser.print_help(sys.stderr)
        return 2
    from .. import log as wlog

    wlog.setup(args.verbose - args.quiet)
    reconfigure = getattr(sys.stderr, "reconfigure", None)
    if reconfigure is not None:  # a message quoting a non-UTF-8 name never fails to print
        reconfigure(errors="backslashreplace")
    ctx = Context(out=None, json=args.json, debug=args.debug, command=args.command)
    prog = f"upd {args.command}"
    t0 = time.perf_counter()
    try:
        check_names(args._parser, args)
        check_values(args._parser, args)
        ctx.out = out_path(args.out)
        summary = args._run(args, ctx)
    except WorkbenchError as e:
        if args.debug:
            log.exception("failed")
        if isinstance(e, InputError):  # rejected input leaves no empty output folder behind
            ctx.remove_empty_created()
        if isinstance(getattr(e, "summary", None), dict):  # what was done is still shown
            _emit(e.summary, args.json, t0)
        sys.stderr.write(f"{prog}: error: {e}\n")
        return e.exit_code
    except KeyboardInterrupt:
        sys.stderr.write(f"{prog}: interrupted; finished work is kept, run again to resume\n")
        return 130
    except Exception as e:  # noqa: BLE001 - the CLI reports every failure in one line
        if args.debug:
            log.exception("failed")
        sys.stderr.write(
            f"{prog}: internal error: {type(e).__name__}: {e} "
            "(rerun with --debug for the traceback)\n"
        )
        if wlog.mpi_size() > 1:
            # An InputError/SolveError is raised on every rank at once (the checks are
            # collective); anything else (a PETSc error on one rank, a bug) may be raised on
            # this rank only, and the others would wait in a collective call for ever.
            from mpi4py import MPI

            sys.stderr.write(f"{prog}: rank {wlog.mpi_rank()} failed; aborting all ranks\n")
            sys.stderr.flush()
            MPI.COMM_WORLD.Abort(1)
        return 1
    _emit(summary, args.json, t0)
    return 0


def _emit(summary: dict[str, Any] | None, as_json: bool, t0: float) -> None:
    """Print a command's summary on stdout (JSON or human-readable; rank 0 only)."""
    from .. import log as wlog

    summary = {} if summary is None else summary
    summary.setdefault("wall_s", round(time.perf_counter() - t0, 3))
    if wlog.mpi_rank() != 0:
        return  # under mpirun the summary is printed once, by rank 0
    if as_json:
        sys.stdout.write(json.dumps(summary, indent=2, default=to_jsonable) + "\n")
    else:
        sys.stdout.write(_human(json.loads(json.dumps(summary, default=to_jsonable))) + "\n")
    sys.stdout.flush()


def out_path(text: str | None) -> Path | None:
    """``--out`` as a path; an empty one is refused (it would mean the current folder)."""
    if text is None:
        return None
    if not str(text).strip():
        raise InputError(
            "--out",
            str(text),
            "a folder name",
            "an empty --out would write into the current folder",
        )
    return Path(text)


def check_names(parser: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """Every file or folder name given is UTF-8 (HDF5, gmsh, JSON and HTML need it)."""
    for a in parser._actions:  # noqa: SLF001 - argparse has no public list of actions
        v = getattr(args, a.dest, None)
        for item in v if isinstance(v, list) else [v]:
            if isinstance(item, (str, Path)):
                shown = utf8_name(str(item))
                if shown is not None:
                    name = a.option_strings[-1] if a.option_strings else (a.metavar or a.dest)
                    raise InputError(
                        name,
                        _Shown(shown),
                        "a UTF-8 name",
                        "it has bytes that are not UTF-8; rename it",
                    )


class _Shown(str):
    """A name shown in an error as it is (its escapes written once, not doubled)."""

    def __repr__(self) -> str:
        return f"'{self}'"


def num(text: str) -> float | str:
    """argparse ``type`` for numbers: a float if it parses, else the text.

    Range and type checks happen in the library, which names the parameter
    and the allowed range; this keeps one message for the CLI and the API.
    """
    try:
        return float(text)
    except ValueError:
        return text


if __name__ == "__main__":
    sys.exit(main())

"""``upd report``: the HTML report of a study folder."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..errors import InputError

HELP = "write the self-contained HTML report of a study folder"
DESCRIPTION = """Gather a study folder's figures, tables, inputs, software versions and
stage timings into one HTML file (figures embedded) that opens from disk.
`upd study` runs this at its end; run it again after editing or resuming."""


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("dir", type=Path, metavar="DIR", help="a folder written by upd study")


def run(args: argparse.Namespace, ctx) -> dict:
    from ..render.report import write_report

    if not args.dir.is_dir():
        raise InputError("DIR", str(args.dir), "an existing study folder")
    target = write_report(args.dir, (ctx.out / "report.html") if ctx.out else None)
    return {"report": str(target), "bytes": target.stat().st_size}

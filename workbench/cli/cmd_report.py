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
    p.add_argument(
        "--screenshot",
        type=Path,
        metavar="PNG",
        help="also write the report's first screen, as a 1280 x 900 browser window shows it "
        "(headless chromium), to PNG, and check that the answer table and the headline "
        "chart are on it",
    )


def run(args: argparse.Namespace, ctx) -> dict:
    from ..render.report import write_report

    if not args.dir.is_dir():
        raise InputError("DIR", str(args.dir), "an existing study folder")
    check_manifest(args.dir / "manifest.json")
    if not ctx.out:  # the report goes into DIR: it must take a file
        from ..io import unwritable

        why = unwritable(args.dir)
        if why is not None:
            raise InputError(
                "DIR", str(args.dir), "a study folder you can write to (or give --out)", why
            )
    target = write_report(args.dir, (ctx.out_dir(".") / "report.html") if ctx.out else None)
    out = {"report": str(target), "bytes": target.stat().st_size}
    if args.screenshot is not None:
        from ..render.browser import first_screen, screenshot

        png = screenshot(target, args.screenshot)
        fs = first_screen(target)
        out["screenshot"] = str(png)
        out["first_screen"] = {
            "loaded": fs.loaded,
            "page_area_px": list(fs.viewport),
            "answer_table_on_screen": fs.on_screen("answer-table"),
            "headline_chart_on_screen": fs.on_screen("headline-chart"),
            "images": fs.images,
            "broken_images": fs.broken_images,
        }
    return out


REQUIRED = ("title", "sections")  # what every study writes and the report cannot do without


def check_manifest(path: Path) -> dict:
    """The parsed ``manifest.json``; an unreadable or malformed one is an InputError."""
    import json

    if not path.is_file():
        raise InputError(
            "DIR",
            str(path.parent),
            "a study folder containing manifest.json (written by upd study)",
        )
    try:
        m = json.loads(path.read_bytes().decode("utf-8"))
    except UnicodeDecodeError as e:
        raise InputError(
            "manifest",
            str(path),
            "a UTF-8 JSON file written by upd study",
            f"byte {e.start} is not UTF-8; run upd study again",
        ) from None
    except ValueError as e:
        raise InputError(
            "manifest",
            str(path),
            "a JSON file written by upd study",
            f"{e}; run upd study again to rewrite it",
        ) from None
    except OSError as e:
        raise InputError("manifest", str(path), "a readable file", e.strerror or "") from None
    shapes = {
        "sections": list,
        "summary": list,
        "timings": dict,
        "inputs": dict,
        "versions": dict,
        "sources": dict,
    }
    if not isinstance(m, dict):
        raise InputError(
            "manifest",
            str(path),
            "a JSON object written by upd study",
            f"it holds a {type(m).__name__}",
        )
    for key, typ in shapes.items():
        if key in m and not isinstance(m[key], typ):
            raise InputError(
                f"manifest {key}",
                m[key] if len(str(m[key])) < 40 else "...",
                f"a JSON {'array' if typ is list else 'object'} (in {path})",
            )
    missing = [k for k in REQUIRED if k not in m]
    if missing:
        raise InputError(
            "manifest",
            str(path),
            "a manifest written by upd study (with " + ", ".join(REQUIRED) + ")",
            "it has no " + ", ".join(missing) + "; run upd study again to rewrite it",
        )
    if not isinstance(m["title"], str):
        raise InputError("manifest title", m["title"], f"a JSON string (in {path})")
    for i, sec in enumerate(m.get("sections", [])):
        if not isinstance(sec, dict):
            raise InputError(f"manifest sections[{i}]", sec, f"a JSON object (in {path})")
    return m

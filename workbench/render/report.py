"""One self-contained HTML report per study folder.

The study runner writes ``DIR/manifest.json``; :func:`write_report` turns it
into ``DIR/report.html`` with every figure embedded (base64 PNG), every
table inlined from its CSV (or markdown) file, the inputs with where each
came from, the software versions and the compute time of each stage. The
file opens from disk in any browser: no server, no external resource.

Manifest layout (all paths relative to DIR)::

    {
      "title": str, "subtitle": str, "created": ISO time,
      "summary": [str, ...],                     # headline lines
      "inputs": {option: value}, "sources": {option: origin},
      "inputs_used": [{"option", "value", "unit", "source"}, ...],  # the report's table
                                                 # (workbench.post.inputs.used_inputs)
      "versions": {package: version},
      "timings": {stage: seconds},
      "sections": [
        {"id": str, "title": str, "text": [paragraph, ...],
         "figures": [{"path": "figures/a.png", "caption": str}],
         "tables":  [{"path": "tables/a.csv", "caption": str}]}
      ]
    }
"""

from __future__ import annotations

import base64
import csv
import html
import json
import logging
from pathlib import Path
from typing import Any

from ..errors import InputError
from ..io import write_text

log = logging.getLogger(__name__)

_CSS = """
body{font-family:DejaVu Sans,Helvetica,Arial,sans-serif;margin:0;color:#1d2433;background:#fafbfc}
main{max-width:1180px;margin:0 auto;padding:24px 32px 64px}
h1{font-size:26px;margin:8px 0 4px}h2{font-size:20px;margin:36px 0 8px;border-bottom:2px solid
#d0d7e2;padding-bottom:4px}h3{font-size:15px;margin:18px 0 6px}
.sub{color:#5b6475;margin:0 0 16px}
nav{background:#eef2f7;border-radius:6px;padding:8px 14px;margin:12px 0 20px;font-size:14px}
nav a{margin-right:14px;color:#1f4e9c;text-decoration:none}
figure{margin:14px 0 22px;background:#fff;border:1px solid #e1e6ee;border-radius:6px;padding:10px}
figure img{max-width:100%;height:auto;display:block;margin:0 auto}
figcaption{font-size:13px;color:#3d4656;margin-top:6px}
table{border-collapse:collapse;font-size:12.5px;margin:6px 0 18px;background:#fff}
th,td{border:1px solid #d9dee7;padding:3px 8px;text-align:right}
th{background:#eef2f7;text-align:center}td:first-child,th:first-child{text-align:left}
.tcap{font-size:13px;color:#3d4656;margin:10px 0 2px}
ul.summary li{margin:3px 0}
.scroll{overflow-x:auto}
"""

# The first figure records its decoded size on <body> from its own load
# event, so a headless browser test can check that it really rendered. An
# image's load event always fires before the document's, so the attribute
# is there whenever the browser reports the page loaded.
_FIRST_ONLOAD = (
    "document.body.setAttribute('data-first-figure',this.naturalWidth+'x'+this.naturalHeight)"
)


def _esc(x: Any) -> str:
    return html.escape(str(x))


def _fmt(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, list):
        return ", ".join(_fmt(x) for x in v)
    return str(v)


def _table_html(rows: list[list[str]]) -> str:
    if not rows:
        return "<p>(empty table)</p>"
    head, body = rows[0], rows[1:]
    out = ["<div class='scroll'><table><thead><tr>"]
    out += [f"<th>{_esc(h)}</th>" for h in head]
    out.append("</tr></thead><tbody>")
    for r in body:
        out.append("<tr>" + "".join(f"<td>{_esc(c)}</td>" for c in r) + "</tr>")
    out.append("</tbody></table></div>")
    return "".join(out)


def _read_table(path: Path) -> list[list[str]]:
    if path.suffix == ".md":
        rows = []
        for line in path.read_text().splitlines():
            line = line.strip()
            if not line.startswith("|") or set(line) <= set("|-: "):
                continue
            rows.append([c.strip() for c in line.strip("|").split("|")])
        return rows
    with path.open(newline="") as fh:
        return [row for row in csv.reader(fh) if row and not row[0].startswith("#")]


def _kv_table(d: dict[str, Any], head: tuple[str, ...], extra: dict[str, Any] | None = None):
    rows = [list(head)]
    for k, v in d.items():
        rows.append([k, _fmt(v)] + ([_fmt(extra.get(k, ""))] if extra is not None else []))
    return _table_html(rows)


def render_html(manifest: dict[str, Any], root: Path) -> str:
    """The report's HTML text for a manifest whose paths are relative to ``root``."""
    title = manifest.get("title", "Study report")
    parts = [
        "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>",
        f"<title>{_esc(title)}</title><style>{_CSS}</style>",
        "</head><body><main>",
        f"<h1>{_esc(title)}</h1>",
        f"<p class='sub'>{_esc(manifest.get('subtitle', ''))} "
        f"{_esc(manifest.get('created', ''))}</p>",
    ]
    sections = manifest.get("sections", [])
    nav = [
        f"<a href='#{_esc(s.get('id', f's{i}'))}'>{_esc(s['title'])}</a>"
        for i, s in enumerate(sections)
    ]
    nav += ["<a href='#inputs'>Inputs</a>", "<a href='#software'>Software and cost</a>"]
    parts.append("<nav>" + "".join(nav) + "</nav>")
    if manifest.get("summary"):
        parts.append("<h2 id='summary'>Summary</h2><ul class='summary'>")
        parts += [f"<li>{_esc(s)}</li>" for s in manifest["summary"]]
        parts.append("</ul>")
    n_fig = n_tab = 0
    for i, s in enumerate(sections):
        parts.append(f"<h2 id='{_esc(s.get('id', f's{i}'))}'>{_esc(s['title'])}</h2>")
        for para in s.get("text", []):
            parts.append(f"<p>{_esc(para)}</p>")
        for t in s.get("tables", []):
            p = root / t["path"]
            if not p.is_file():
                raise InputError("manifest table", t["path"], f"an existing file under {root}")
            parts.append(f"<p class='tcap'>{_esc(t.get('caption', ''))}</p>")
            parts.append(_table_html(_read_table(p)))
            n_tab += 1
        for f in s.get("figures", []):
            p = root / f["path"]
            if not p.is_file():
                raise InputError("manifest figure", f["path"], f"an existing file under {root}")
            data = base64.b64encode(p.read_bytes()).decode("ascii")
            onload = f' onload="{_FIRST_ONLOAD}"' if n_fig == 0 else ""
            parts.append(
                f"<figure><img{onload} alt='{_esc(f.get('caption', p.name))}' "
                f"data-file='{_esc(f['path'])}' src='data:image/png;base64,{data}'>"
                f"<figcaption>{_esc(f.get('caption', ''))}</figcaption></figure>"
            )
            n_fig += 1
    parts.append("<h2 id='inputs'>Inputs</h2>")
    if not manifest.get("inputs_used") and manifest.get("inputs", {}).get("kind"):
        # a manifest written before inputs_used existed: resolve it now (from the
        # geometry and contact files as they are today)
        from ..post.inputs import used_inputs

        try:
            manifest = dict(
                manifest, inputs_used=used_inputs(manifest["inputs"], manifest.get("sources", {}))
            )
        except Exception as e:  # noqa: BLE001 - the raw table below is still right
            log.warning("inputs of an older manifest not resolved: %s", e)
    if manifest.get("inputs_used"):
        parts.append(
            "<p class='sub'>The values every case was computed with (options left "
            "unset take the geometry and contact files' values, named in the last "
            "column); only the options of this kind of study.</p>"
        )
        rows = [["option", "value", "unit", "from"]]
        rows += [
            [r["option"], _fmt(r["value"]), r.get("unit", ""), r.get("source", "")]
            for r in manifest["inputs_used"]
        ]
        parts.append(_table_html(rows))
    else:  # a manifest written before the inputs_used list existed
        parts.append(
            _kv_table(
                manifest.get("inputs", {}), ("option", "value", "from"), manifest.get("sources", {})
            )
        )
    parts.append("<h2 id='software'>Software and cost</h2><h3>Versions</h3>")
    parts.append(_kv_table(manifest.get("versions", {}), ("package", "version")))
    parts.append("<h3>Compute time of each stage</h3>")
    timings = {k: f"{v:.2f}" for k, v in manifest.get("timings", {}).items()}
    parts.append(_kv_table(timings, ("stage", "wall time (s)")))
    parts.append(f"<p class='sub'>{n_fig} figures, {n_tab} tables.</p>")
    parts.append("</main></body></html>")
    return "\n".join(parts)


def write_report(study_dir: str | Path, out: str | Path | None = None) -> Path:
    """Write ``report.html`` for a study folder holding a ``manifest.json``."""
    root = Path(study_dir)
    mpath = root / "manifest.json"
    if not mpath.is_file():
        raise InputError(
            "DIR", str(root), "a study folder containing manifest.json (written by upd study)"
        )
    manifest = json.loads(mpath.read_text())
    target = Path(out) if out else root / "report.html"
    write_text(target, render_html(manifest, root))
    log.info("wrote %s", target)
    return target

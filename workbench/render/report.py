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
         "tables":  [{"path": "tables/a.csv", "caption": str}],
         "kind": "answer", "notes": [str, ...]}   # optional: the first screen
      ],
      "machine": {"cpus": int, "load": [...]}     # optional: load averages of the run
    }

A section of kind "answer" (a comparison's answer: sentences, the answer
table, how sure, the headline chart) comes first, the table and the notes
on the left and the chart beside them, so that it fills the first screen
of a 1280 x 900 window; the table of contents follows it, then the other
sections. Tables from CSV files are shown with 4 significant digits and
readable headers (``peak_amplitude_mm`` -> "peak amplitude (mm)"); the
files keep every digit. A small script records, once the page has
loaded, the position of the first-screen elements (``data-rect``) and the
number of images that failed to decode (``data-broken-images`` on
<body>): what a headless-browser test reads.
"""

from __future__ import annotations

import base64
import csv
import html
import json
import logging
import math
from pathlib import Path
from typing import Any

from ..errors import InputError
from ..io import write_text

log = logging.getLogger(__name__)

_CSS = """
body{font-family:DejaVu Sans,Helvetica,Arial,sans-serif;margin:0;color:#1d2433;background:#fafbfc}
main{max-width:1240px;margin:0 auto;padding:14px 24px 64px}
h1{font-size:23px;margin:4px 0 2px}h2{font-size:20px;margin:36px 0 8px;border-bottom:2px solid
#d0d7e2;padding-bottom:4px}h3{font-size:15px;margin:18px 0 6px}
.sub{color:#5b6475;margin:0 0 10px;font-size:13px}
nav{background:#eef2f7;border-radius:6px;padding:8px 14px;margin:18px 0 20px;font-size:14px}
nav a{margin-right:14px;color:#1f4e9c;text-decoration:none;white-space:nowrap}
figure{margin:14px 0 22px;background:#fff;border:1px solid #e1e6ee;border-radius:6px;padding:10px}
figure img{max-width:100%;height:auto;display:block;margin:0 auto}
figcaption{font-size:13px;color:#3d4656;margin-top:6px}
table{border-collapse:collapse;font-size:12.5px;margin:6px 0 18px;background:#fff;max-width:100%}
th,td{border:1px solid #d9dee7;padding:3px 7px;text-align:right;overflow-wrap:break-word}
th{background:#eef2f7;text-align:center;font-weight:600}
td:first-child,th:first-child{text-align:left}
td.group{background:#f4f6f9;font-weight:600;text-align:left}
.tcap{font-size:13px;color:#3d4656;margin:10px 0 2px}
ul.summary li{margin:3px 0}
table.inputs td{text-align:left}table.inputs td:nth-child(1){width:26%}
table.inputs td:nth-child(2){width:40%}table.inputs td:nth-child(3){white-space:nowrap}
section.answer{background:#fff;border:2px solid #1f4e9c;border-radius:8px;padding:6px 14px 8px}
section.answer h2{margin:4px 0 4px;border:0;font-size:19px}
section.answer p{margin:3px 0;font-size:13.5px}
.ans-grid{display:flex;flex-wrap:wrap;gap:14px;align-items:flex-start}
.ans-left{flex:1 1 560px;min-width:0}.ans-right{flex:0 1 520px;min-width:0}
.ans-right figure{margin:0;padding:4px;border:0}
.ans-left table{font-size:12px;margin:4px 0 6px}
.ans-left th,.ans-left td{padding:2px 5px}
ul.sure{margin:2px 0 0;padding-left:18px;font-size:12.5px}ul.sure li{margin:2px 0}
.ans-left h3{margin:6px 0 2px;font-size:14px}
"""

# The first figure records its decoded size on <body> from its own load
# event, so a headless browser test can check that it really rendered. An
# image's load event always fires before the document's, so the attribute
# is there whenever the browser reports the page loaded.
_FIRST_ONLOAD = (
    "document.body.setAttribute('data-first-figure',this.naturalWidth+'x'+this.naturalHeight)"
)

# After the load: every image that failed to decode, the window's size and where each
# first-screen element lies (what tests/test_report_browser.py reads from the DOM).
_LAYOUT_SCRIPT = """<script>
window.addEventListener('load', function () {
  var b = document.body, im = document.images, bad = 0, i;
  for (i = 0; i < im.length; i++) { if (!im[i].complete || im[i].naturalWidth === 0) bad++; }
  b.setAttribute('data-images', im.length);
  b.setAttribute('data-broken-images', bad);
  b.setAttribute('data-viewport', window.innerWidth + 'x' + window.innerHeight);
  var els = document.querySelectorAll('[data-first-screen]');
  for (i = 0; i < els.length; i++) {
    var r = els[i].getBoundingClientRect();
    els[i].setAttribute('data-rect', [r.left, r.top, r.right, r.bottom].map(Math.round).join(','));
  }
  b.setAttribute('data-laid-out', 'yes');
});
</script>"""


def _esc(x: Any) -> str:
    return html.escape(str(x))


def _fmt(v: Any) -> str:
    """A value for a report cell: numbers to 4 significant digits (never -0), yes/no."""
    from ..post.tables import num

    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return num(v, 4)
    if isinstance(v, list):
        return ", ".join(_fmt(x) for x in v)
    return str(v)


_SUFFIX_UNITS = (
    ("_n_per_m2", "N/m per m"),
    ("_n_per_m3", "N/m per m^2"),
    ("_mm_per_n", "mm/N"),
    ("_mm", "mm"),
    ("_hz", "Hz"),
    ("_mj", "mJ"),
    ("_pct", "%"),
    ("_deg", "deg"),
    ("_s", "s"),
    ("_n", "N"),
)


def _header(h: str) -> str:
    """A CSV column name as a reader's header: 'hbm_peak_amplitude_mm' -> 'hbm peak
    amplitude (mm)'; a header with spaces is kept."""
    if " " in h or "_" not in h:
        return h
    for suffix, unit in _SUFFIX_UNITS:
        if h.endswith(suffix):
            return f"{h[: -len(suffix)].replace('_', ' ')} ({unit})"
    return h.replace("_", " ")


def _cell(c: str) -> str:
    """A CSV cell for the page: a number written with more than 5 significant digits is
    shown with 4 (the file keeps them all), True/False read yes/no, -0 reads 0."""
    t = c.strip()
    if t in ("True", "False"):
        return "yes" if t == "True" else "no"
    try:
        v = float(t)
    except ValueError:
        return c
    if not math.isfinite(v):
        return "n/a" if v != v else t
    if v == 0.0:
        return "0"
    if t.lstrip("+-").isdigit():  # a count: every digit
        return t
    mant = t.lower().split("e")[0].lstrip("+-").replace(".", "").lstrip("0")
    return _fmt(v) if len(mant.rstrip("0")) > 5 else t


def _table_html(rows: list[list[str]], attrs: str = "", raw: bool = False) -> str:
    """An HTML table; unless ``raw``, headers and number cells are made readable."""
    if not rows:
        return "<p>(empty table)</p>"
    head, body = rows[0], rows[1:]
    if not raw:
        head = [_header(h) for h in head]
        body = [[_cell(c) for c in r] for r in body]
    out = [f"<table{attrs}><thead><tr>"]
    out += [f"<th>{_esc(h)}</th>" for h in head]
    out.append("</tr></thead><tbody>")
    for r in body:
        out.append("<tr>" + "".join(f"<td>{_esc(c)}</td>" for c in r) + "</tr>")
    out.append("</tbody></table>")
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
    return _table_html(rows, raw=True)


def _figure_html(root: Path, f: dict, first: bool, attrs: str = "") -> str:
    p = root / f["path"]
    if not p.is_file():
        raise InputError("manifest figure", f["path"], f"an existing file under {root}")
    data = base64.b64encode(p.read_bytes()).decode("ascii")
    onload = f' onload="{_FIRST_ONLOAD}"' if first else ""
    return (
        f"<figure{attrs}><img{onload} alt='{_esc(f.get('caption', p.name))}' "
        f"data-file='{_esc(f['path'])}' src='data:image/png;base64,{data}'>"
        f"<figcaption>{_esc(f.get('caption', ''))}</figcaption></figure>"
    )


def _table_file(root: Path, t: dict, attrs: str = "") -> str:
    p = root / t["path"]
    if not p.is_file():
        raise InputError("manifest table", t["path"], f"an existing file under {root}")
    return f"<p class='tcap'>{_esc(t.get('caption', ''))}</p>" + _table_html(_read_table(p), attrs)


def _answer_html(s: dict, root: Path) -> str:
    """The first screen: sentences, the answer table and how sure, the chart beside them."""
    parts = [
        f"<section class='answer' id='{_esc(s.get('id', 'answer'))}' data-first-screen='answer'>",
        f"<h2>{_esc(s['title'])}</h2>",
    ]
    parts += [f"<p>{_esc(t)}</p>" for t in s.get("text", [])]
    parts.append("<div class='ans-grid'><div class='ans-left'>")
    for t in s.get("tables", []):
        parts.append(_table_file(root, t, " data-first-screen='answer-table'"))
    if s.get("notes"):
        parts.append("<h3>How sure</h3><ul class='sure'>")
        parts += [f"<li>{_esc(n)}</li>" for n in s["notes"]]
        parts.append("</ul>")
    parts.append("</div><div class='ans-right'>")
    for k, f in enumerate(s.get("figures", [])):
        parts.append(_figure_html(root, f, k == 0, " data-first-screen='headline-chart'"))
    parts.append("</div></div></section>")
    return "".join(parts)


def _inputs_html(manifest: dict[str, Any]) -> str:
    rows = manifest["inputs_used"]
    out = [
        "<p class='sub'>Every value the cases were computed with, read from the objects the "
        "solve used (also in results.h5, group case/inputs of each case, and in "
        "summary.json); the last column says where each came from.</p>",
        "<table class='inputs'><thead><tr><th>input</th><th>value</th><th>unit</th>"
        "<th>from</th></tr>"
        "</thead><tbody>",
    ]
    group = None
    for r in rows:
        g = r.get("group")
        if g and g != group:
            out.append(f"<tr><td class='group' colspan='4'>{_esc(g)}</td></tr>")
            group = g
        unit = r.get("unit", "")
        out.append(
            "<tr>"
            + "".join(
                f"<td>{_esc(c)}</td>"
                for c in (r["option"], _fmt(r["value"]), "" if unit == "1" else unit)
            )
            + f"<td>{_esc(r.get('source', ''))}</td></tr>"
        )
    out.append("</tbody></table>")
    return "".join(out)


def _machine_note(manifest: dict[str, Any]) -> str:
    """A sentence on the machine's load while the cases ran, if the run recorded it."""
    m = manifest.get("machine") or {}
    loads = [float(x) for x in m.get("load", []) if x == x]
    cpus = int(m.get("cpus") or 0)
    if not loads or not cpus:
        return ""
    top = max(loads)
    from ..post.tables import num

    if top > cpus:
        return (
            f"The machine was loaded while these times were measured: load average up to "
            f"{num(top, 3)} on {cpus} cores (more runnable processes than cores), so they are "
            "longer than on a quiet machine."
        )
    return (
        f"Load average while the cases ran: at most {num(top, 3)} on {cpus} cores (this run "
        "included): the times are those of a machine that was not overloaded."
    )


def render_html(manifest: dict[str, Any], root: Path) -> str:
    """The report's HTML text for a manifest whose paths are relative to ``root``."""
    title = manifest.get("title", "Study report")
    parts = [
        "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>",
        "<meta name='viewport' content='width=device-width, initial-scale=1'>",
        f"<title>{_esc(title)}</title><style>{_CSS}</style>",
        "</head><body><main>",
        f"<h1>{_esc(title)}</h1>",
        f"<p class='sub'>{_esc(manifest.get('subtitle', ''))} "
        f"{_esc(manifest.get('created', ''))}</p>",
    ]
    sections = manifest.get("sections", [])
    answer = [s for s in sections if s.get("kind") == "answer"]
    rest = [s for s in sections if s.get("kind") != "answer"]
    n_fig = n_tab = 0
    for s in answer:
        parts.append(_answer_html(s, root))
        n_fig += len(s.get("figures", []))
        n_tab += len(s.get("tables", []))
    nav = [f"<a href='#{_esc(s.get('id', 'answer'))}'>{_esc(s['title'])}</a>" for s in answer]
    if manifest.get("summary") and not answer:
        nav.append("<a href='#summary'>Summary</a>")
    nav += [
        f"<a href='#{_esc(s.get('id', f's{i}'))}'>{_esc(s['title'])}</a>"
        for i, s in enumerate(rest)
    ]
    nav += ["<a href='#inputs'>Inputs</a>", "<a href='#software'>Software and cost</a>"]
    parts.append("<nav><b>Contents</b>&nbsp;&nbsp;" + " ".join(nav) + "</nav>")
    if manifest.get("summary") and not answer:
        parts.append("<h2 id='summary'>Summary</h2><ul class='summary'>")
        parts += [f"<li>{_esc(s)}</li>" for s in manifest["summary"]]
        parts.append("</ul>")
    for i, s in enumerate(rest):
        parts.append(f"<h2 id='{_esc(s.get('id', f's{i}'))}'>{_esc(s['title'])}</h2>")
        for para in s.get("text", []):
            parts.append(f"<p>{_esc(para)}</p>")
        for t in s.get("tables", []):
            parts.append(_table_file(root, t))
            n_tab += 1
        for f in s.get("figures", []):
            parts.append(_figure_html(root, f, n_fig == 0))
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
        parts.append(_inputs_html(manifest))
    else:  # a manifest written before the inputs_used list existed
        parts.append(
            _kv_table(
                manifest.get("inputs", {}), ("option", "value", "from"), manifest.get("sources", {})
            )
        )
    parts.append("<h2 id='software'>Software and cost</h2><h3>Versions</h3>")
    parts.append(_kv_table(manifest.get("versions", {}), ("package", "version")))
    parts.append("<h3>Compute time of each stage</h3>")
    note = _machine_note(manifest)
    if note:
        parts.append(f"<p>{_esc(note)}</p>")
    timings = {k: f"{v:.2f}" for k, v in manifest.get("timings", {}).items()}
    parts.append(_kv_table(timings, ("stage", "wall time (s)")))
    parts.append(f"<p class='sub'>{n_fig} figures, {n_tab} tables.</p>")
    parts.append("</main>" + _LAYOUT_SCRIPT + "</body></html>")
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

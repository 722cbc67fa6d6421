"""The study options as a Markdown reference (``docs/OPTIONS.md``), from their declarations.

``python -m workbench.studies.engine.options_doc > docs/OPTIONS.md`` writes it;
``tests/test_options_doc.py`` checks that the file in the repository is what
the declarations give, so the reference cannot drift from the code. One
table per option group, in ``upd study --help`` order: the option (the study
file's key and the flag), its type, default, allowed values, unit, role (what
it shapes: the model, a case's solve, the cases, or only the study) and help.
"""

from __future__ import annotations

import sys
from typing import Any

from ..kinds import all_kinds
from .spec import OPTIONS, range_text

TYPES = {
    "float": "number",
    "int": "whole number",
    "bool": "true/false",
    "str": "text",
    "path": "file",
    "floats": "numbers",
    "ints": "whole numbers",
    "strs": "texts",
    "percent": "per cent",
}


def _cell(text: Any) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _default(v: Any) -> str:
    if v is None:
        return "(from the files or the solver)"
    if isinstance(v, list):
        return "[" + ", ".join(map(str, v)) + "]" if v else "[]"
    return str(v).lower() if isinstance(v, bool) else str(v)


def _allowed(o: Any) -> str:
    if o.choices:
        return ", ".join(o.choices)
    return range_text(o).removeprefix("; ").replace("%%", "%")


def options_markdown() -> str:
    """The reference text (Markdown)."""
    lines = [
        "# Study options",
        "",
        "Generated from the option declarations by",
        "`python -m workbench.studies.engine.options_doc > docs/OPTIONS.md`",
        "(`tests/test_options_doc.py` checks it is current): the shared options",
        "(`workbench/study_options.py`, `SharedOptions`), the contact laws' parameters",
        "(`workbench/contact/law_params.py` and each law's `PARAMS`) and each study",
        "kind's own (`workbench/studies/kinds/<kind>/options.py`). A study file names",
        "an option by its key (`mesh-size = 9.0`), the command line by the flag",
        "(`--mesh-size 9`). Role: what the option shapes (`model`: the mesh, the",
        "reduction, the contact, in the model's cache key; `solve`: a case's curve,",
        "in its key; `case`: each case takes one of its values; `study`: what is",
        "computed and shown).",
        "",
        "Study kinds: " + ", ".join(f"`{k.name}` ({k.description})" for k in all_kinds()) + ".",
    ]
    group = None
    for o in OPTIONS:
        if o.group != group:
            group = o.group
            lines += [
                "",
                f"## {group} options",
                "",
                "| option | type | default | allowed | unit | role | help |",
                "|---|---|---|---|---|---|---|",
            ]
        row = (
            f"`{o.name}`",
            TYPES[o.kind] + (" or none" if o.optional else ""),
            _default(o.default),
            _allowed(o),
            o.unit,
            o.role,
            o.help.replace("%%", "%"),
        )
        lines.append("| " + " | ".join(_cell(c) for c in row) + " |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    sys.stdout.write(options_markdown())

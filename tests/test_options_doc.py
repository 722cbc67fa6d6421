"""docs/OPTIONS.md is what the option declarations give (regenerate it after a change)."""

from __future__ import annotations

from conftest import ROOT

from workbench.studies.engine.options_doc import options_markdown
from workbench.studies.engine.spec import OPTIONS


def test_the_options_reference_is_current():
    text = (ROOT / "docs" / "OPTIONS.md").read_text()
    assert text == options_markdown(), (
        "docs/OPTIONS.md is stale: python -m workbench.studies.engine.options_doc > docs/OPTIONS.md"
    )


def test_every_option_has_one_row_with_its_unit():
    text = options_markdown()
    for o in OPTIONS:
        rows = [line for line in text.splitlines() if line.startswith(f"| `{o.name}` |")]
        assert len(rows) == 1, o.name
        assert f"| {o.unit} | {o.role} |" in rows[0], o.name

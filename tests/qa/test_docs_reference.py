"""The docs' scene-key reference (docs/_ext/scene_keys.py) lists every key of the schema.

Independent of the generator's own list of tables: the schema module is searched for its
key tables (every module-level dict of :class:`Key`, or of such dicts per kind) and the
keyed functions are called for every registered name (integrator options, law parameters,
friction); each must appear as one section of the generated text with exactly its keys.
"""
from __future__ import annotations

import re
import sys

import pytest

import paths
from ffrmbs_app.scene_file import schema
from ffrmbs_app.scene_file.schema import Key

sys.path.insert(0, str(paths.REPO / "docs" / "_ext"))
import scene_keys  # noqa: E402  (the docs' extension, from docs/_ext)


PARTS = {"BODY_HEAD": schema.BODY}      # a table that is the head of each table of another


def schema_tables() -> list[frozenset]:
    """The key sets of every table the schema defines."""
    found = []
    for name, value in vars(schema).items():
        if name in PARTS:
            assert all(set(value) <= set(whole) for whole in PARTS[name].values())
            continue
        if name.startswith("_") or not isinstance(value, dict) or not value:
            continue
        if all(isinstance(v, Key) for v in value.values()):
            found.append(frozenset(value))
        elif all(isinstance(v, dict) and all(isinstance(k, Key) for k in v.values()) for v in value.values()):
            found += [frozenset(v) for v in value.values()]
    found += [frozenset(schema.option_keys(n)) for n in schema.INTEGRATORS.names()]
    found += [frozenset({**schema.law_keys(n), **schema.friction_keys(n)}) for n in schema.LAWS.names()]
    return found


def generated_sections(text: str) -> dict[str, frozenset]:
    """{section title: the keys in its table's first column} of the generated RST."""
    sections, title = {}, None
    lines = text.splitlines()
    for line, under in zip(lines, lines[1:] + [""]):
        if under and set(under) == {"~"} and len(under) == len(line):
            title = line
            sections[title] = set()
        m = re.match(r"^   \* - ``([^`]+)``$", line)
        if m and title is not None:
            sections[title].add(m.group(1))
    return {t: frozenset(k) for t, k in sections.items()}


def test_every_schema_table_is_a_generated_section():
    sections = set(generated_sections(scene_keys.reference_text()).values())
    missing = [sorted(keys) for keys in schema_tables() if keys not in sections and keys]
    assert not missing, f"schema tables without their section in the docs: {missing}"


def test_every_schema_key_appears_with_its_default_and_choices():
    text = scene_keys.reference_text()
    assert "Tables of keys" in text and schema.__doc__.strip().splitlines()[0] in text
    for keys in schema_tables():
        for name in keys:
            assert f"``{name}``" in text
    for name in schema.INTEGRATORS.names() + schema.LAWS.names() + tuple(schema.QUANTITIES):
        assert f'"{name}"' in text


DATA = paths.REPO / "docs" / "validation" / "_data"


def test_validation_page_shows_every_case_row_and_figure_of_the_data():
    """The generated validation page against the committed output it is made from: every
    case a section, every row's error in it, every PNG of the directory shown."""
    import json

    validation_report = pytest.importorskip("validation_report")
    data = DATA / "quick"
    doc = json.loads((data / "results.json").read_text())
    page = validation_report.validation_page(data, "../_data/quick", "CMD")
    sections = re.findall(r"^## (\S+)$", page, flags=re.M)
    assert sections == list(doc["cases"])
    shown = set(re.findall(r"\]\(\.\./_data/quick/([^)]+\.png)\)", page))
    assert shown == {p.name for p in data.glob("*.png")}
    for row in doc["rows"]:
        if row["error"] is not None:
            assert f"{row['error']:.3e}" in page
    assert "CMD" in page and doc["date"] in page


def test_stability_page_shows_every_row():
    import json

    validation_report = pytest.importorskip("validation_report")
    data = DATA / "stability"
    doc = json.loads((data / "stability.json").read_text())
    page = validation_report.stability_page(data, "../_data/stability", "CMD")
    for row in doc["rows"]:
        assert f"| {row['case']} |" in page
    assert f"{sum(r['passed'] for r in doc['rows'])} of {len(doc['rows'])} cases passed" in page

"""The repository's test fixtures, ``tests/fixtures/``: scene files (``scenes/``), meshes
(``meshes/``) and body files, read by the tests and by the audits (:mod:`qa.fault_audit`),
so that a planted input and a test's input are the same file."""

from pathlib import Path

FIXTURES = Path(__file__).resolve().parents[1] / "tests" / "fixtures"


def fixture_path(name: str) -> Path:
    """The fixture file ``name`` (relative to ``tests/fixtures/``, e.g. ``"scenes/beam_block_bob.toml"``)."""
    path = FIXTURES / name
    if not path.is_file():
        raise FileNotFoundError(f"no fixture file {name!r} in {FIXTURES}")
    return path


def fixture_text(name: str) -> str:
    """The text of the fixture file ``name`` (see :func:`fixture_path`)."""
    return fixture_path(name).read_text()


def edited(text: str, *edits) -> str:
    """``text`` with each ``(old, new)`` edit applied; ``old`` must occur exactly once (a
    one-line change of a fixture, spelled out where it is made)."""
    for old, new in edits:
        if text.count(old) != 1:
            raise ValueError(f"edit {old!r} does not match exactly once")
        text = text.replace(old, new)
    return text

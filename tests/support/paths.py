"""Where the tests find the repository's files, wherever a test module sits under tests/.
The fixture files (``tests/fixtures/``) are read with :func:`qa.fixtures.fixture_text`,
which the audits share."""

from pathlib import Path

from qa.fixtures import FIXTURES

TESTS = Path(__file__).resolve().parents[1]
REPO = TESTS.parent
EXAMPLES = REPO / "examples"

__all__ = ["EXAMPLES", "FIXTURES", "REPO", "TESTS"]

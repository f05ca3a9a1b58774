"""The commands and snippets of the README and of the docs' hand-written pages
(docs/getting_started.md, docs/guide/*.md) work as written (the rules of reading them are
in tests/support/readme_commands.py).

Every shell command they show must parse: ffrmbs arguments by the CLI's own parser,
modules and example scripts must exist, pip extras must be in setup.cfg. The fenced
commands of each document are then run as written, in its order, in a temporary
directory laid out like a fresh clone (so that a plot finds the run before it), except
usage synopses, the commands listed in NOT_RUN with the reason, and those that another
test runs as written and checks (RUN_BY). Self-contained Python snippets run there too; the others must compile and their imports must exist. The runs
use the caller's body cache ($FFRMBS_CACHE or ~/.cache/ffrmbs): the first-run path with an
empty cache is another test's.
"""

import os
import shutil
import subprocess
import sys
import time

import pytest

import paths
import readme_commands as rc

REPO = paths.REPO
README = REPO / "README.md"
GETTING_STARTED = REPO / "docs" / "getting_started.md"
DOCUMENTS = [README, GETTING_STARTED, *sorted((REPO / "docs" / "guide").glob("*.md"))]
README_LINES = 150       # the README is short: what ffrmbs is, set-up, a tour, headline figures, the docs
TIMEOUT_S = 300          # per command or snippet; a command slower than this belongs in NOT_RUN

# command prefix -> why the test does not run it (it is still parsed)
NOT_RUN = {
    "python3 -m pip install": "installs into the environment; the extras it names are checked against setup.cfg",
    "python3 -m pytest": "the whole test suite, which holds this test",
    "python3 -m sphinx": "the docs build, which .ci/run runs (warnings are errors, the gallery included)",
    "python3 -m qa.fault_audit": "minutes of bad inputs, each in its own process; tests/qa/test_fault_audit.py runs "
                                 "its classifier, its case table and real cases end to end",
    "ffrmbs run examples/scenes/bouncing_ball.toml --set scene.t_end=1 --checkpoint-every 1 --no-check "
    "--out out/long --resume": "continues a killed run: needs a kill after the first checkpoint; kill -9 and "
                               "resume are tested in tests/e2e/test_resume.py",
    "python3 -m distributed.cli.dask_scheduler": "a server that runs until stopped; tests/e2e/test_sweep.py starts a "
                                                 "scheduler with workers (LocalCluster)",
    "python3 -m distributed.cli.dask_worker": "a server that runs until stopped, and needs a scheduler at host",
    "ffrmbs sweep examples/scenes/point_mass_beam.toml --set body.beam.modes=10,20,40": "needs a scheduler at "
        "host:8786; --scheduler is tested against a LocalCluster's in tests/e2e/test_sweep.py",
}


# command, as written -> the test that runs it so and checks what it prints and writes
RUN_BY = {
    "ffrmbs run": "tests/e2e/test_cli.py::test_main_job_runs_the_point_mass_on_the_beam",
}


def _text(document):
    return document.read_text(encoding="utf-8")


def _items(document):
    """(document, item) of each fenced command and snippet of ``document``."""
    return [(document, item) for item in rc.items(_text(document))]


def _commands(documents=DOCUMENTS):
    """(document, command) of every fenced command of ``documents``."""
    return [(d, item) for document in documents for d, item in _items(document) if isinstance(item, rc.Command)]


def _all_commands():
    """(document, command) of every fenced and inline command of every document."""
    return _commands() + [(d, c) for d in DOCUMENTS for c in rc.inline_commands(_text(d))]


def _not_run_reason(command):
    if command.text in RUN_BY:
        return f"run as written by {RUN_BY[command.text]}"
    return next((why for prefix, why in NOT_RUN.items() if command.text.startswith(prefix)), None)


def _where(document, item):
    shown = item.text if isinstance(item, rc.Command) else item.source.splitlines()[0] + " ..."
    return f"{document.relative_to(REPO)}, line {item.line}: `{shown}`"


SAMPLE = """Try `ffrmbs run --help` or `OPENBLAS_NUM_THREADS=1 ffrmbs run SCENE.toml`; `ffrmbs plot` plots.

```sh
# a comment line
A=1 ffrmbs run --out o \\
    --dt 1e-4   # a trailing comment
pip install '.[test]' && ffrmbs info b#c; ffrmbs info 'c&&d;e' 
ffrmbs validate --out o [--quick] [--only NAME[,NAME]]
```

```python
from x import y
print(y, [data for _ in range(2)], lambda t: t)
```

```
output, not read
```
"""


def test_reader_rules_on_a_sample():
    """The rules of tests/support/readme_commands.py on a README whose reading is known."""
    items = rc.items(SAMPLE)
    commands = [(c.line, c.text, c.synopsis) for c in items if isinstance(c, rc.Command)]
    assert commands == [(5, "A=1 ffrmbs run --out o --dt 1e-4", False),
                        (7, "pip install '.[test]'", False), (7, "ffrmbs info b#c", False), (7, "ffrmbs info 'c&&d;e'", False),
                        (8, "ffrmbs validate --out o [--quick] [--only NAME[,NAME]]", True)]
    assert items[0].forms() == [({"A": "1"}, ["ffrmbs", "run", "--out", "o", "--dt", "1e-4"])]
    assert items[1].forms() == [({}, ["pip", "install", ".[test]"])]
    assert items[4].forms() == [({}, ["ffrmbs", "validate", "--out", "o"]),
                                ({}, ["ffrmbs", "validate", "--out", "o", "--quick", "--only", "NAME,NAME"])]
    (snippet,) = [s for s in items if isinstance(s, rc.Snippet)]
    assert (snippet.line, snippet.imports(), snippet.free_names()) == (12, [("x", "y")], {"data"})
    inline = [(c.line, c.text, c.synopsis) for c in rc.inline_commands(SAMPLE)]
    assert inline == [(1, "ffrmbs run --help", False), (1, "OPENBLAS_NUM_THREADS=1 ffrmbs run SCENE.toml", True),
                      (1, "ffrmbs plot", False)]
    assert rc.parse_problem(["ffrmbs", "plot"], REPO) is None                      # names the subcommand
    assert "required: --out" in rc.parse_problem(["ffrmbs", "validate", "--quick"], REPO)
    assert "no extra nope" in rc.parse_problem(["pip", "install", ".[test,nope]"], REPO)
    assert "no file" in rc.parse_problem(["python3", "examples/none.py"], REPO)
    assert "no module" in rc.parse_problem(["python3", "-m", "validation.none"], REPO)
    assert "pipe" in rc.parse_problem(["python3", "examples/gallery/plot_03_modal_impact.py", "|", "head"], REPO)


def test_documents_have_commands_and_snippets():
    """The reader finds what is there (a broken fence would make every other test vacuous):
    every fence of every document is closed, each document shows commands, the README a
    snippet too; the guide has its pages."""
    assert len(DOCUMENTS) > 8
    for document in DOCUMENTS:
        text = _text(document)
        fences = sum(1 for line in text.splitlines() if line.strip().startswith("```"))
        blocks = rc.fenced_blocks(text)
        assert 2 * len(blocks) == fences, document
        shell = [b for b in blocks if b[0] in rc.SHELL_FENCES]
        assert len(_commands([document])) >= len(shell), document
    assert _commands([README]) and any(isinstance(item, rc.Snippet) for item in rc.items(_text(README)))


def test_readme_is_short():
    assert len(_text(README).splitlines()) <= README_LINES


def test_ci_runs_the_readme_test_and_docs_commands():
    """.ci/run runs the README's test command and its docs build exactly as the README shows them."""
    shown = [line.strip() for lang, _, body in rc.fenced_blocks(_text(README)) if lang in ("sh", "bash", "console")
             for line in body.splitlines() if "pytest" in line or "sphinx" in line]
    ci = [line.strip() for line in (REPO / ".ci" / "run").read_text().splitlines()]
    assert len(shown) == 2 and all(line in ci for line in shown), (shown, ci)


def test_every_command_parses():
    problems = []
    for document, command in _all_commands():
        for _, words in command.forms():
            problem = rc.parse_problem(words, REPO)
            if problem:
                problems.append(f"{_where(document, command)}: {problem}")
    if problems:
        pytest.fail("\n".join(problems), pytrace=False)


def test_every_command_is_run_or_says_why_not():
    """A fenced command is run unless it is a synopsis, NOT_RUN says why not or RUN_BY names
    the test that runs it as written; an entry of either that no longer matches a command
    of any document (or a test) is stale."""
    commands = _commands()
    unknown = [_where(d, c) for d, c in commands
               if not c.synopsis and not _not_run_reason(c) and _argv(c.forms()[0][1]) is None]
    stale = [prefix for prefix in NOT_RUN if not any(c.text.startswith(prefix) for _, c in commands)]
    problems = [f"{where}: this test cannot run it; teach _argv to, or list it in NOT_RUN" for where in unknown]
    problems += [f"NOT_RUN entry {prefix!r} matches no command" for prefix in stale]
    problems += [f"RUN_BY entry {text!r} is no command of any document" for text in RUN_BY
                 if not any(c.text == text for _, c in commands)]
    for text, test in RUN_BY.items():
        path, name = test.split("::")
        if f"def {name}(" not in (REPO / path).read_text(encoding="utf-8"):
            problems.append(f"RUN_BY entry {text!r}: no test {test}")
    if problems:
        pytest.fail("\n".join(problems), pytrace=False)


def test_python_snippets_compile_and_import():
    problems = []
    for document, snippet in ((d, i) for doc in DOCUMENTS for d, i in _items(doc) if isinstance(i, rc.Snippet)):
        try:
            snippet.code()
        except SyntaxError as exc:
            problems.append(f"{_where(document, snippet)}: {exc}")
            continue
        problems += [f"{_where(document, snippet)}: {p}" for p in
                     filter(None, (rc.import_problem(m, n) for m, n in snippet.imports()))]
        if snippet.free_names():
            problems.append(f"{_where(document, snippet)}: a fragment (uses "
                            f"{', '.join(sorted(snippet.free_names()))} without defining them); every snippet "
                            "runs as written")
    if problems:
        pytest.fail("\n".join(problems), pytrace=False)


def _argv(words):
    """The process to start for a command's words, with this checkout's code, or None."""
    if words[0] == "ffrmbs":
        return [sys.executable, "-m", "ffrmbs_app.cli", *words[1:]]
    if words[0] in ("python3", "python"):
        return [sys.executable, *words[1:]]
    return None


WRITTEN_INTO = ("examples",)        # the guide preprocesses example parts into examples/scenes/
IGNORED = ("plate", "plate_hole", "channel", "__pycache__")     # bodies a user made there (.gitignore)


def _fresh_clone(tmp):
    """A directory laid out like a fresh clone: the repository's tracked top-level entries
    (all non-hidden ones without git) as symlinks — copies for those the README's commands
    write into — so outputs land in tmp. The commands import the code from the repository
    itself (first on ``PYTHONPATH`` by tests/conftest.py; ``PYTHONSAFEPATH`` keeps the
    working directory off ``sys.path``), whose kernels are in numba's cache, keyed by the
    source's directory."""
    try:
        tracked = subprocess.run(["git", "ls-files"], cwd=REPO, capture_output=True, text=True, check=True).stdout
        names = {path.split("/")[0] for path in tracked.splitlines()}
    except (OSError, subprocess.CalledProcessError):
        names = {p.name for p in REPO.iterdir()}
    tmp.mkdir()
    for name in sorted(n for n in names if not n.startswith(".")):
        if name in WRITTEN_INTO:
            shutil.copytree(REPO / name, tmp / name, ignore=shutil.ignore_patterns(*IGNORED))
        else:
            (tmp / name).symlink_to(REPO / name)
    return tmp


def _to_run(document):
    """The items of ``document`` this test runs: its snippets and its fenced commands but
    synopses, NOT_RUN, RUN_BY and — on the getting-started page — the README's own commands,
    which the README's run covers."""
    shown_in_readme = {c.text for _, c in _commands([README])} if document == GETTING_STARTED else set()
    return [item for _, item in _items(document)
            if isinstance(item, rc.Snippet)
            or not (item.synopsis or _not_run_reason(item) or item.text in shown_in_readme)]


def test_the_readme_shows_commands_this_test_runs():
    """The README's run below is never empty (other documents may show none to run)."""
    assert _to_run(README)


@pytest.mark.slow
@pytest.mark.parametrize("document", [pytest.param(d, marks=pytest.mark.xdist_group(f"readme-{d.stem}"))
                                      for d in DOCUMENTS if _to_run(d)], ids=lambda d: str(d.relative_to(REPO)))
def test_commands_run_as_written(document, tmp_path):
    """The document's fenced commands and self-contained snippets, in its order, each exits 0
    (one xdist group per document: they share nothing, so the workers can split them)."""
    items = _to_run(document)
    work = _fresh_clone(tmp_path / "clone")
    env = {**os.environ, "FFRMBS_PROGRESS": "0", "PYTHONSAFEPATH": "1"}     # PYTHONPATH: tests/conftest.py
    failures = []
    for item in items:
        if isinstance(item, rc.Snippet):
            argv, extra = [sys.executable, "-c", item.source], {}
        else:
            extra, words = item.forms()[0]
            argv = _argv(words)
        start = time.perf_counter()
        try:
            done = subprocess.run(argv, cwd=work, env={**env, **extra}, capture_output=True, text=True,
                                  timeout=TIMEOUT_S)
        except subprocess.TimeoutExpired:
            failures.append(f"{_where(document, item)}: still running after {TIMEOUT_S} s "
                            "(make it cheaper or list it in NOT_RUN)")
            continue
        if done.returncode != 0:
            failures.append(f"{_where(document, item)}: exit {done.returncode}\n{done.stderr.strip()[-2000:]}")
        print(f"{done.returncode}  {time.perf_counter() - start:6.1f} s  {_where(document, item)}")
    if failures:
        pytest.fail("\n\n".join(failures), pytrace=False)

"""The README's commands and Python snippets as tests/e2e/test_readme.py reads them.

Rules (the README's shell text is read as a shell would, plus one convention):

- Fenced blocks marked ``sh`` (or ``bash``, ``shell``) hold commands; blocks marked
  ``python`` (or ``py``) hold snippets; other fences are output or data and are not read.
- In a shell block, backslash continuations are joined, an unquoted ``#`` at the start of
  a word begins a comment, and ``&&`` or ``;`` separate commands. Pipes and redirections
  are not read (a command using them is reported, so that this module learns them).
- Inline code spans in the prose that start with a command word (``ffrmbs``, ``python3``,
  ``pip``, possibly after ``VAR=value`` words) are commands too, shown but not meant to
  be run here. An inline span that is only ``ffrmbs SUBCOMMAND`` names a subcommand.
- A command holding unquoted ``[ ... ]`` (a shell would glob it, so it cannot be meant
  literally) or an UPPERCASE placeholder word (``NAME``, ``SCENE.toml``) is a usage
  synopsis: it is never run; its shortest form (bracketed parts dropped) and its longest
  form (brackets removed, their contents kept) must both parse.
"""

import argparse
import ast
import builtins
import configparser
import contextlib
import importlib
import importlib.util
import io
import re
import shlex
import symtable
from dataclasses import dataclass, field
from pathlib import Path

SHELL_FENCES = {"sh", "bash", "shell"}
PYTHON_FENCES = {"python", "py"}
COMMAND_WORDS = {"ffrmbs", "python3", "python", "pip"}
_ENV_WORD = re.compile(r"[A-Za-z_][A-Za-z0-9_]*=")
_PLACEHOLDER = re.compile(r"\b[A-Z][A-Z0-9_]*[A-Z]\b")
_FENCE = re.compile(r"^(\s*)```(\S*)\s*$")
_INLINE = re.compile(r"`([^`\n]+)`")
_SHELL_OPERATORS = {"|", "||", "&", ">", ">>", "<", "2>", "2>&1"}
_PIP_TARGET = re.compile(r"\.(?:\[([A-Za-z0-9_,-]+)\])?")


@dataclass(frozen=True)
class Command:
    """One command as the README shows it."""

    line: int                  # README line (1-based) where it starts
    raw: str                   # its text, comments removed

    @property
    def text(self) -> str:
        return " ".join(self.raw.split())

    @property
    def synopsis(self) -> bool:
        unquoted = "".join(c for c, quoted in _chars(self.raw) if not quoted)
        return "[" in unquoted or bool(_PLACEHOLDER.search(" ".join(self.forms()[0][1])))

    def forms(self) -> list[tuple[dict, list[str]]]:
        """(environment, words) of each form to check: the command itself, or a
        synopsis's shortest and longest forms."""
        kept, shortest, depth = [], [], 0
        for c, quoted in _chars(self.raw):
            if not quoted and c == "[":
                depth += 1
            elif not quoted and c == "]":
                depth -= 1
            else:
                kept.append(c)
                if depth == 0:
                    shortest.append(c)
        texts = [self.raw] if "".join(kept) == self.raw else ["".join(shortest), "".join(kept)]
        return [_split_env(shlex.split(text)) for text in texts]


@dataclass(frozen=True)
class Snippet:
    """One fenced Python block."""

    line: int                  # README line (1-based) of its first source line
    source: str = field(repr=False)

    def code(self):
        return compile(self.source, f"README.md, line {self.line}", "exec")

    def imports(self) -> list[tuple[str, str | None]]:
        """(module, name) of every ``from module import name``; (module, None) of ``import module``."""
        found = []
        for node in ast.walk(ast.parse(self.source)):
            if isinstance(node, ast.ImportFrom):
                found += [(node.module, alias.name) for alias in node.names]
            elif isinstance(node, ast.Import):
                found += [(alias.name, None) for alias in node.names]
        return found

    def free_names(self) -> set[str]:
        """Names the snippet uses but neither defines, imports nor gets from builtins
        (``data``, ``patch``): a snippet without any is self-contained and can run."""
        top = symtable.symtable(self.source, "README.md", "exec")
        bound = {s.get_name() for s in top.get_symbols() if s.is_assigned() or s.is_imported()}
        used, tables = set(), [top]
        while tables:
            table = tables.pop()
            used |= {s.get_name() for s in table.get_symbols()
                     if s.is_referenced() and (table is top or s.is_global())}
            tables += table.get_children()
        return used - bound - set(dir(builtins))


def _chars(text):
    """(character, inside quotes) of each character of shell text; quote marks count as quoted."""
    quote = None
    for c in text:
        if quote:
            yield c, True
            quote = None if c == quote else quote
        elif c in "'\"":
            quote = c
            yield c, True
        else:
            yield c, False


def _split_env(words):
    """({VAR: value} of the leading VAR=value words, the words after them)."""
    env = {}
    while words and _ENV_WORD.match(words[0]):
        name, value = words[0].split("=", 1)
        env[name] = value
        words = words[1:]
    return env, words


def _shell_commands(text, line):
    """The commands of one logical shell line: comment dropped, split at && and ;."""
    kept, previous = [], (" ", True)
    for c, quoted in _chars(text):
        if not quoted and c == "#" and previous[0].isspace():
            break
        if not quoted and c == "&" and previous == ("&", False):
            kept[-1], c = "\0", ""                         # && ends a command
        kept.append("\0" if not quoted and c == ";" else c)
        previous = (c, quoted)
    pieces = "".join(kept).split("\0")
    return [Command(line, piece.strip()) for piece in pieces if piece.strip()]


def fenced_blocks(readme: str) -> list[tuple[str, int, str]]:
    """(language, line of the first content line, content) of every fenced block."""
    blocks, lang, start, body = [], None, 0, []
    for number, text in enumerate(readme.splitlines(), 1):
        match = _FENCE.match(text)
        if lang is None and match:
            lang, start, body = match.group(2).lower(), number + 1, []
        elif lang is not None and text.strip() == "```":
            blocks.append((lang, start, "\n".join(body) + "\n"))
            lang = None
        elif lang is not None:
            body.append(text)
    return blocks


def items(readme: str) -> list:
    """The fenced shell commands and Python snippets, in README order."""
    found = []
    for lang, start, body in fenced_blocks(readme):
        if lang in PYTHON_FENCES:
            found.append(Snippet(start, body))
        elif lang in SHELL_FENCES:
            logical, first = "", None
            for number, text in enumerate(body.splitlines(), start):
                first = number if first is None else first
                if text.endswith("\\"):
                    logical += text[:-1] + " "
                    continue
                found += _shell_commands(logical + text, first)
                logical, first = "", None
    return found


def inline_commands(readme: str) -> list[Command]:
    """Commands shown in inline code spans outside fenced blocks."""
    found, inside = [], False
    for number, text in enumerate(readme.splitlines(), 1):
        if _FENCE.match(text) or (inside and text.strip() == "```"):
            inside = not inside
            continue
        if inside:
            continue
        for span in _INLINE.findall(text):
            words = span.split()
            while words and _ENV_WORD.match(words[0]):
                words = words[1:]
            if words and words[0] in COMMAND_WORDS and len(words) > 1:
                found += _shell_commands(span, number)
    return found


def parse_problem(words: list[str], repo: Path) -> str | None:
    """Why a command's words would not start as written, or None: ffrmbs arguments by the
    CLI's own parser, ``python3 -m MODULE`` by the module's existence (and its parser
    when it is the CLI's), ``python3 FILE`` by the file's existence, ``pip install`` by
    the extras named in setup.cfg."""
    prog, args = words[0], words[1:]
    if set(words) & _SHELL_OPERATORS:
        return "a pipe or redirection, which tests/support/readme_commands.py does not read"
    if prog == "ffrmbs":
        return _ffrmbs_problem(args)
    if prog in ("python3", "python") and args[:1] == ["-m"] and len(args) > 1:
        module, rest = args[1], args[2:]
        if module == "pip":
            return _pip_problem(rest, repo)
        if module in CLI_MODULES:
            return _ffrmbs_problem(CLI_MODULES[module] + rest)
        if importlib.util.find_spec(module) is None:
            return f"no module {module!r}"
        return None
    if prog in ("python3", "python") and args:
        return None if (repo / args[0]).is_file() else f"no file {args[0]} in the repository"
    if prog == "pip":
        return _pip_problem(args, repo)
    return f"unknown command {prog!r} (tests/support/readme_commands.py reads ffrmbs, python3 and pip)"


# modules that run the CLI: ``python3 -m MODULE ARGS`` is ``ffrmbs PREFIX ARGS``
CLI_MODULES = {"ffrmbs_app.cli": [], "validation.bench": ["bench"]}


def _ffrmbs_problem(args):
    from ffrmbs_app.cli import build_parser

    if len(args) == 1 and not args[0].startswith("-"):
        return None if args[0] in _subcommands(build_parser()) else f"no subcommand {args[0]!r}"
    err = io.StringIO()
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            build_parser().parse_args(args)
    except SystemExit as exc:
        if exc.code:
            return err.getvalue().strip().splitlines()[-1]
    return None


def _subcommands(parser):
    (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return sub.choices


def _pip_problem(args, repo):
    if args[:1] != ["install"] or len(args) < 2:
        return "only `pip install .[EXTRAS]` is read"
    extras = configparser.ConfigParser()
    extras.read(repo / "setup.cfg")
    known = set(extras["options.extras_require"]) if extras.has_section("options.extras_require") else set()
    for target in (a for a in args[1:] if not a.startswith("-")):
        match = _PIP_TARGET.fullmatch(target)
        if not match:
            return f"pip target {target!r} is not this repository (. or .[EXTRAS])"
        missing = set(filter(None, (match.group(1) or "").split(","))) - known
        if missing:
            return f"setup.cfg has no extra {', '.join(sorted(missing))} (extras: {', '.join(sorted(known))})"
    return None


def import_problem(module: str, name: str | None) -> str | None:
    """Why ``from module import name`` (or ``import module``) fails, or None."""
    try:
        imported = importlib.import_module(module)
    except ImportError as exc:
        return f"import {module}: {exc}"
    if name is not None and not hasattr(imported, name):
        return f"{module} has no {name!r}"
    return None

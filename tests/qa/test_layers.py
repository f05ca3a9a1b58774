"""The package layers of DESIGN.md, read from the source: every ``import`` statement of
every module (module-level and inside functions) is parsed with :mod:`ast` and checked
against the allowed directions

    ffrmbs (errors, version) <- preprocess <- contours <- contact <- mbs <- ffrmbs_app <- validation

(an arrow points from a package to one it may use). ``ffrmbs_app.cli`` may launch
``validation`` from inside a command function; nothing else of the product imports it.
``ffrmbs.sweep()`` imports ``ffrmbs_app.sweeps`` inside the function (the one entry point
of the bottom layer into the application; ``import ffrmbs`` stays free of it).
Module-level imports between our modules form no cycle.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import paths

ROOT = paths.REPO

# package -> the packages of ours it may import (besides itself)
ALLOWED = {
    "ffrmbs": set(),
    "preprocess": {"ffrmbs"},
    "contours": {"ffrmbs", "preprocess"},
    "contact": {"ffrmbs", "preprocess", "contours"},
    "mbs": {"ffrmbs", "preprocess", "contours", "contact"},
    "ffrmbs_app": {"ffrmbs", "preprocess", "contours", "contact", "mbs"},
    "validation": {"ffrmbs", "preprocess", "contours", "contact", "mbs", "ffrmbs_app"},
    "qa": {"ffrmbs", "preprocess", "contours", "contact", "mbs", "ffrmbs_app", "validation"},
}
LAUNCHES_VALIDATION = "ffrmbs_app.cli"     # may import validation inside a function
LAZY_ENTRY_POINTS = {"ffrmbs": {"ffrmbs_app.sweeps"}}   # ffrmbs.sweep(): inside the function only


def module_name(path: Path, root=ROOT) -> str:
    parts = list(path.relative_to(root).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def is_module(name: str, root=ROOT) -> bool:
    base = root.joinpath(*name.split("."))
    return base.with_suffix(".py").is_file() or (base / "__init__.py").is_file()


def imports(path: Path, root=ROOT):
    """(imported module, line, at module level) for every import in ``path``; for
    ``from X import Y`` the module X.Y when Y is a module, else X."""
    tree = ast.parse(path.read_text(), str(path))
    name = module_name(path, root)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    top = {id(node) for node in tree.body}
    top |= {id(n) for node in tree.body if isinstance(node, (ast.If, ast.Try))
            for n in ast.walk(node)}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name, node.lineno, id(node) in top
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                yield (sub if is_module(sub, root) else target), node.lineno, id(node) in top


def our_modules():
    return sorted(p for pkg in ALLOWED for p in (ROOT / pkg).rglob("*.py"))


def test_every_package_of_ours_is_in_the_rules():
    packages = {p.parent.name for p in ROOT.glob("*/__init__.py")} - {"tests"}
    assert packages == set(ALLOWED), f"packages without a layer rule: {packages ^ set(ALLOWED)}"


def upward_imports(path: Path, root=ROOT) -> list[str]:
    """The imports of ``path`` that break the layer rules, one line each."""
    name = module_name(path, root)
    package = name.split(".")[0]
    faults = []
    for target, line, module_level in imports(path, root):
        other = target.split(".")[0]
        if other == package or other not in ALLOWED:
            continue
        if other == "validation" and name == LAUNCHES_VALIDATION and not module_level:
            continue
        if target in LAZY_ENTRY_POINTS.get(name, ()) and not module_level:
            continue
        if other not in ALLOWED[package]:
            faults.append(f"{path.relative_to(root)}:{line} imports {target} ({package} may not use {other})")
    return faults


@pytest.mark.parametrize("path", our_modules(), ids=lambda p: str(p.relative_to(ROOT)))
def test_imports_point_down(path):
    faults = upward_imports(path)
    assert not faults, "\n".join(faults)


def import_cycles(paths, root=ROOT) -> list[str]:
    """The cycles of module-level imports among ``paths``, as "a -> b -> a"."""
    modules = {module_name(p, root): p for p in paths}
    graph = {name: {t for t, _, top in imports(path, root) if top and t in modules and t != name}
             for name, path in modules.items()}
    state, cycles = {}, []

    def visit(node, stack):
        state[node] = "open"
        stack.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == "open":
                cycles.append(" -> ".join(stack[stack.index(nxt):] + [nxt]))
            elif nxt not in state:
                visit(nxt, stack)
        stack.pop()
        state[node] = "done"

    for node in sorted(graph):
        if node not in state:
            visit(node, [])
    return cycles


def test_no_module_level_import_cycles():
    cycles = import_cycles(our_modules())
    assert not cycles, "\n".join(cycles)


def test_the_rules_catch_upward_imports(tmp_path):
    """The checker itself, on a made-up tree: a contours module importing mbs at module
    level, a relative import climbing into ffrmbs_app, and an application module other
    than the CLI importing validation inside a function are all reported."""
    (tmp_path / "contours").mkdir()
    (tmp_path / "ffrmbs_app").mkdir()
    probe = tmp_path / "contours" / "probe.py"
    probe.write_text("from mbs.rotations import skew\nfrom ..ffrmbs_app import job\n")
    job = tmp_path / "ffrmbs_app" / "job.py"
    job.write_text("def run():\n    import validation.harness\n")
    cli = tmp_path / "ffrmbs_app" / "cli.py"
    cli.write_text("def validate():\n    from validation import run_validation\n")
    faults = upward_imports(probe, tmp_path)
    assert len(faults) == 2 and "contours may not use mbs" in faults[0] and "ffrmbs_app" in faults[1]
    assert upward_imports(job, tmp_path) == ["ffrmbs_app/job.py:2 imports validation.harness "
                                             "(ffrmbs_app may not use validation)"]
    assert upward_imports(cli, tmp_path) == []


def test_the_cycle_check_finds_a_cycle(tmp_path):
    (tmp_path / "mbs").mkdir()
    (tmp_path / "mbs" / "__init__.py").write_text("")
    (tmp_path / "mbs" / "a.py").write_text("from .b import f\n")
    (tmp_path / "mbs" / "b.py").write_text("import numpy\nfrom mbs.a import g\n")
    paths = sorted((tmp_path / "mbs").glob("*.py"))
    assert import_cycles(paths, tmp_path) == ["mbs.a -> mbs.b -> mbs.a"]

"""The package layers of DESIGN.md, read from the source: every ``import`` statement of
every module (module-level and inside functions) is parsed with :mod:`ast` and checked
against the allowed directions

    ffrmbs (errors, version) <- preprocess <- contours <- contact <- mbs <- ffrmbs_app <- validation

(an arrow points from a package to one it may use). ``ffrmbs_app.cli`` may launch
``validation`` from inside a command function; nothing else of the product imports it.
The imports between our modules, module-level and inside functions alike, form no circle
(a function-level import that closes one only hides it until the function runs), and no
module imports another's private name (``from x import _y``) or reads one off a module it
imported (``x._y``), nor reaches a private attribute of an object of another module's
class (``body._f``; found without types, by the names a module defines itself): a name
another module needs is public, with its docstring.
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


def module_name(path: Path, root=ROOT) -> str:
    parts = list(path.relative_to(root).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def is_module(name: str, root=ROOT) -> bool:
    base = root.joinpath(*name.split("."))
    return base.with_suffix(".py").is_file() or (base / "__init__.py").is_file()


def from_target(node: ast.ImportFrom, path: Path, root=ROOT) -> str:
    """The module X of ``from X import ...`` in ``path``, relative imports resolved."""
    if not node.level:
        return node.module
    name = module_name(path, root)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    base = package.split(".")
    base = base[:len(base) - node.level + 1]
    return ".".join(base + ([node.module] if node.module else []))


def imports(path: Path, root=ROOT):
    """(imported module, line, at module level) for every import in ``path``; for
    ``from X import Y`` the module X.Y when Y is a module, else X."""
    tree = ast.parse(path.read_text(), str(path))
    top = {id(node) for node in tree.body}
    top |= {id(n) for node in tree.body if isinstance(node, (ast.If, ast.Try))
            for n in ast.walk(node)}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name, node.lineno, id(node) in top
        elif isinstance(node, ast.ImportFrom):
            target = from_target(node, path, root)
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
        if other not in ALLOWED[package]:
            faults.append(f"{path.relative_to(root)}:{line} imports {target} ({package} may not use {other})")
    return faults


@pytest.mark.parametrize("path", our_modules(), ids=lambda p: str(p.relative_to(ROOT)))
def test_imports_point_down(path):
    faults = upward_imports(path)
    assert not faults, "\n".join(faults)


def import_cycles(paths, root=ROOT) -> list[str]:
    """The cycles of imports (module-level and inside functions) among ``paths``, as
    "a -> b -> a"."""
    modules = {module_name(p, root): p for p in paths}
    graph = {name: {t for t, _, _ in imports(path, root) if t in modules and t != name}
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


def test_no_import_cycles():
    cycles = import_cycles(our_modules())
    assert not cycles, "\n".join(cycles)


def is_private(name: str) -> bool:
    return name.startswith("_") and not name.startswith("__")


def private_reaches(path: Path, root=ROOT) -> list[str]:
    """The private names of another of our modules that ``path`` imports (``from x import
    _y``) or reads off a module of ours it imported (``x._y``), one line each. Private
    modules (``from mbs import _kernels``) are modules, not names: they may be imported."""
    tree = ast.parse(path.read_text(), str(path))
    name = module_name(path, root)
    faults, aliases = [], {}        # local name -> our module it is bound to
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            aliases.update({a.asname: a.name for a in node.names if a.asname and a.name.split(".")[0] in ALLOWED})
        elif isinstance(node, ast.ImportFrom):
            target = from_target(node, path, root)
            if target.split(".")[0] not in ALLOWED:
                continue
            for alias in node.names:
                if is_module(f"{target}.{alias.name}", root):
                    aliases[alias.asname or alias.name] = f"{target}.{alias.name}"
                elif is_private(alias.name) and target != name:
                    faults.append(f"{path.relative_to(root)}:{node.lineno} imports {alias.name} from {target}")
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id in aliases \
                and is_private(node.attr):
            faults.append(f"{path.relative_to(root)}:{node.lineno} reads {aliases[node.value.id]}.{node.attr}")
    return faults


@pytest.mark.parametrize("path", our_modules(), ids=lambda p: str(p.relative_to(ROOT)))
def test_no_private_name_crosses_modules(path):
    faults = private_reaches(path)
    assert not faults, "\n".join(faults)


def foreign_attributes(path: Path, root=ROOT) -> list[str]:
    """The private attributes (``x._y``, read or written) that ``path`` reaches on objects
    of other modules' classes, one line each: a private name that ``path`` neither defines
    (a function, a class, a name it binds) nor sets on ``self`` or ``cls``. Without types
    this is a heuristic: ``super()._y`` (the own class's parents), ``self._y`` and
    ``cls._y`` pass, and so do the attributes of another library's modules
    (``import akantu as aka``, ``aka._static``: that library's own API)."""
    tree = ast.parse(path.read_text(), str(path))
    own, foreign = set(), set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            own.add(node.name)
        elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
            own.add(node.id)
        elif isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store) \
                and isinstance(node.value, ast.Name) and node.value.id in ("self", "cls"):
            own.add(node.attr)
        elif isinstance(node, ast.Import):
            foreign |= {a.asname or a.name.split(".")[0] for a in node.names if a.name.split(".")[0] not in ALLOWED}
        elif isinstance(node, ast.ImportFrom) and not node.level and node.module.split(".")[0] not in ALLOWED:
            foreign |= {a.asname or a.name for a in node.names}
    faults = []
    for node in ast.walk(tree):
        if not (isinstance(node, ast.Attribute) and is_private(node.attr) and node.attr not in own
                and isinstance(node.value, (ast.Name, ast.Attribute))):
            continue
        base = node.value
        while isinstance(base, ast.Attribute):
            base = base.value
        if isinstance(node.value, ast.Name) and node.value.id in ("self", "cls") \
                or isinstance(base, ast.Name) and base.id in foreign:
            continue
        faults.append(f"{path.relative_to(root)}:{node.lineno} reaches {ast.unparse(node)}")
    return faults


@pytest.mark.parametrize("path", our_modules(), ids=lambda p: str(p.relative_to(ROOT)))
def test_no_private_attribute_of_another_modules_class(path):
    faults = foreign_attributes(path)
    assert not faults, "\n".join(faults)


def test_the_rules_catch_upward_imports(tmp_path):
    """The checker itself, on a made-up tree: a contours module importing mbs at module
    level, a relative import climbing into ffrmbs_app, and an application module other
    than the CLI importing validation inside a function are all reported."""
    (tmp_path / "contours").mkdir()
    (tmp_path / "ffrmbs_app").mkdir()
    probe = tmp_path / "contours" / "probe.py"
    probe.write_text("from mbs.bodies.rotations import skew\nfrom ..ffrmbs_app import job\n")
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


def test_the_cycle_check_finds_a_cycle_closed_inside_a_function(tmp_path):
    """Two modules of a made-up tree, one importing the other at module level, the other
    importing it back inside a function: a circle; without the function's import, none."""
    (tmp_path / "ffrmbs_app").mkdir()
    (tmp_path / "ffrmbs_app" / "scene.py").write_text(
        "def load_scene(path):\n    from ffrmbs_app.scene_file import read_scene\n    return read_scene(path)\n")
    (tmp_path / "ffrmbs_app" / "scene_file.py").write_text("from ffrmbs_app.scene import Scene\n")
    paths = sorted((tmp_path / "ffrmbs_app").glob("*.py"))
    assert import_cycles(paths, tmp_path) == ["ffrmbs_app.scene -> ffrmbs_app.scene_file -> ffrmbs_app.scene"]
    (tmp_path / "ffrmbs_app" / "scene.py").write_text("def load_scene(path):\n    return path\n")
    assert import_cycles(paths, tmp_path) == []


def test_the_private_name_check_finds_imports_and_reads(tmp_path):
    """A made-up module importing a private name of another module of ours, absolutely and
    relatively, and reading one off a module it imported, inside a function too, is
    reported; private modules, dunder names, its own names and other packages' are not."""
    (tmp_path / "ffrmbs_app").mkdir()
    (tmp_path / "ffrmbs_app" / "__init__.py").write_text("")
    (tmp_path / "ffrmbs_app" / "export.py").write_text("def _dataset():\n    pass\n")
    (tmp_path / "ffrmbs_app" / "_kernels.py").write_text("def step():\n    pass\n")
    plot = tmp_path / "ffrmbs_app" / "plot.py"
    plot.write_text("from ffrmbs_app.export import _dataset\n"
                    "from .export import _group, open_result\n"
                    "from ffrmbs_app import _kernels, export as ex\n"
                    "from ffrmbs import __version__\n"
                    "from numpy import _NoValue\n"
                    "def draw():\n"
                    "    from ffrmbs_app.plot import _own\n"
                    "    return ex._child, _kernels.step, ex.open_result\n")
    assert private_reaches(plot, tmp_path) == [
        "ffrmbs_app/plot.py:1 imports _dataset from ffrmbs_app.export",
        "ffrmbs_app/plot.py:2 imports _group from ffrmbs_app.export",
        "ffrmbs_app/plot.py:8 reads ffrmbs_app.export._child"]


def test_the_attribute_check_finds_reaches_into_other_classes(tmp_path):
    """A made-up module reading and writing private attributes of objects of another
    module's classes is reported; its own class's privates (on self, cls, another
    instance of it), super()'s and another library's are not."""
    (tmp_path / "mbs").mkdir()
    probe = tmp_path / "mbs" / "probe.py"
    probe.write_text("import numpy as np\n"
                     "class Sphere:\n"
                     "    def __init__(self, body):\n"
                     "        self._r = body.radius\n"
                     "        self.f = body._f\n"
                     "    def same(self, other):\n"
                     "        return other._r == self._r and np._NoValue and super()._prepare()\n"
                     "    def mark(self, contour):\n"
                     "        contour._has_u = True\n"
                     "        return self.body.frame._box0\n")
    assert foreign_attributes(probe, tmp_path) == ["mbs/probe.py:5 reaches body._f",
                                                   "mbs/probe.py:9 reaches contour._has_u",
                                                   "mbs/probe.py:10 reaches self.body.frame._box0"]

"""Assertions per test module, read from the source: ``assert`` statements, ``pytest.raises``
and ``pytest.warns`` blocks, and calls of ``assert_*`` functions (numpy.testing and our own).

Usage::

    python3 -m qa.assertion_counts [--json FILE] [--compare BEFORE.json] [tests]

Modules are keyed by file name, so a count taken before test files moved between folders
compares with one taken after. ``--compare`` prints each module whose count changed and the
totals, and exits 1 if a module lost assertions or disappeared.
"""

from __future__ import annotations

import argparse
import ast
import json
import sys
from pathlib import Path


def _is_assertion_call(node: ast.Call) -> bool:
    func = node.func
    name = func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", "")
    return name in ("raises", "warns") or name.startswith("assert_")


def count_module(path: Path) -> dict:
    """``{"tests": n, "assertions": m}`` of one test module."""
    tree = ast.parse(path.read_text(), filename=str(path))
    tests = sum(isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef)) and n.name.startswith("test")
                for n in ast.walk(tree))
    assertions = sum(isinstance(n, ast.Assert) or (isinstance(n, ast.Call) and _is_assertion_call(n))
                     for n in ast.walk(tree))
    return {"tests": tests, "assertions": assertions}


def count_suite(root: Path) -> dict[str, dict]:
    """Counts of every ``test_*.py`` under ``root``, keyed by file name."""
    return {p.name: count_module(p) for p in sorted(root.rglob("test_*.py"))}


def compare(before: dict[str, dict], after: dict[str, dict]) -> list[str]:
    """Lines of a comparison table; modules that lost assertions or disappeared are marked ``LOST``."""
    lines = [f"{'module':40s} {'before':>7s} {'after':>7s}"]
    for name in sorted(set(before) | set(after)):
        b = before.get(name, {}).get("assertions")
        a = after.get(name, {}).get("assertions")
        if a == b:
            continue
        lost = a is None or (b is not None and a < b)
        lines.append(f"{name:40s} {b if b is not None else '-':>7} {a if a is not None else '-':>7}"
                     + ("  LOST" if lost else ""))
    total_b = sum(v["assertions"] for v in before.values())
    total_a = sum(v["assertions"] for v in after.values())
    lines.append(f"{'total (' + str(len(before)) + ' / ' + str(len(after)) + ' modules)':40s} "
                 f"{total_b:>7d} {total_a:>7d}")
    return lines


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python3 -m qa.assertion_counts", description=__doc__.split("\n")[0])
    parser.add_argument("tests", nargs="?", default="tests", help="folder of the test modules (default: tests)")
    parser.add_argument("--json", help="write the counts to this JSON file")
    parser.add_argument("--compare", help="a JSON file of counts taken before: print what changed")
    args = parser.parse_args(argv)
    counts = count_suite(Path(args.tests))
    if args.json:
        Path(args.json).write_text(json.dumps(counts, indent=1, sort_keys=True) + "\n")
    if args.compare:
        before = json.loads(Path(args.compare).read_text())
        lines = compare(before, counts)
        print("\n".join(lines))
        return 1 if any(line.endswith("LOST") for line in lines) else 0
    for name, c in counts.items():
        print(f"{name:40s} {c['tests']:4d} tests {c['assertions']:5d} assertions")
    print(f"total: {sum(c['tests'] for c in counts.values())} tests, "
          f"{sum(c['assertions'] for c in counts.values())} assertions in {len(counts)} modules")
    return 0


if __name__ == "__main__":
    sys.exit(main())

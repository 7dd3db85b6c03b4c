"""The import rule of docs/design.md, enforced: imports flow one way.

    cli -> formats, part105, rules, motion, cable -> kinematics -> (numpy only)
                           part105, rules -> schema -> step

Every ``import`` in the package is read from the source (module level and inside functions,
since lazy imports are imports too), mapped to the top-level subpackage on each side, and
checked against the allowed edges below. A new edge is a design decision: add it here and to
docs/design.md in the same change, with its reason.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parent.parent / "p105cli"

#: subpackage -> the subpackages it may import (besides itself and the leaf modules below).
ALLOWED = {
    "cli": {"formats", "part105", "rules", "motion", "cable", "kinematics", "schema", "step"},
    "formats": {"part105", "motion", "kinematics", "step"},
    "part105": {"motion", "kinematics", "schema", "step"},
    "rules": {"part105", "kinematics", "schema", "step"},
    "motion": {"kinematics"},
    # the key-point file of a scene is a user-side file: read by formats.poses, the one pose
    # reader that solve --path uses too (issue 10, item 8)
    "cable": {"formats", "kinematics"},
    "kinematics": set(),
    "schema": {"step"},
    "step": set(),
    # the test-data generator (the independent oracle): nothing in the package imports it
    "corpus": {"part105", "kinematics", "step"},
    "manpages": {"cli"},
    "__main__": {"cli"},
}
#: leaf modules anyone may import: they import nothing of the package
LEAVES = {"fileio", "__init__"}


def _module_name(path: Path) -> str:
    rel = path.relative_to(PACKAGE.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _imports(path: Path, source: str | None = None):
    """(line, absolute module name) of every import in ``path`` (or in ``source`` as if it
    were that file)."""
    text = path.read_text(encoding="utf-8") if source is None else source
    tree = ast.parse(text, str(path))
    mod = _module_name(path)
    package = mod if path.name == "__init__.py" else mod.rpartition(".")[0]
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                yield node.lineno, a.name
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if node.module is None or target == "p105cli":
                # ``from . import x`` / ``from p105cli import x``: each name may be a module
                for a in node.names:
                    yield node.lineno, f"{target}.{a.name}"
            else:
                yield node.lineno, target


def _subpackage(module: str) -> str | None:
    """The top-level module of the package that ``module`` lies in (``"__init__"`` for names
    of the package itself, such as ``p105cli.__version__``); None outside the package."""
    parts = module.split(".")
    if parts[0] != "p105cli":
        return None
    if len(parts) == 1:
        return "__init__"
    head = parts[1]
    if (PACKAGE / head).is_dir() or (PACKAGE / f"{head}.py").is_file():
        return head
    return "__init__"


def _edges():
    for path in sorted(PACKAGE.rglob("*.py")):
        src = _subpackage(_module_name(path)) if path.name != "__init__.py" or path.parent != PACKAGE \
            else "__init__"
        for line, target in _imports(path):
            dst = _subpackage(target)
            if dst is None or dst == src:
                continue
            yield path.relative_to(PACKAGE.parent), line, src, dst, target


def test_every_subpackage_is_known():
    names = {p.stem if p.is_file() else p.name for p in PACKAGE.iterdir()
             if (p.is_dir() and (p / "__init__.py").exists()) or p.suffix == ".py"}
    unknown = names - set(ALLOWED) - LEAVES
    assert not unknown, f"new top-level modules {sorted(unknown)}: give them a place in ALLOWED"


def test_imports_flow_one_way():
    bad = [f"{path}:{line}: {src} -> {dst} ({target})" for path, line, src, dst, target in _edges()
           if dst not in LEAVES and dst not in ALLOWED.get(src, set())]
    assert not bad, "imports against the rule of docs/design.md:\n" + "\n".join(bad)


def test_nothing_imports_the_corpus():
    bad = [f"{path}:{line}: {target}" for path, line, src, dst, target in _edges()
           if dst == "corpus" and src != "corpus"]
    assert not bad, "\n".join(bad)


def test_the_allowed_graph_has_no_cycle():
    seen, stack = set(), set()

    def visit(n):
        if n in stack:
            pytest.fail(f"cycle through {n}")
        if n in seen:
            return
        stack.add(n)
        for m in ALLOWED.get(n, ()):
            visit(m)
        stack.discard(n)
        seen.add(n)

    for n in ALLOWED:
        visit(n)


def test_the_walker_sees_lazy_and_relative_imports():
    # the rule is only as good as the walk: function-level and relative imports must be seen
    probe = PACKAGE / "kinematics" / "probe.py"
    src = "import numpy\ndef f():\n    from ..rules import kinematics\n    from .pairs import PAIRS\n"
    found = [t for _, t in _imports(probe, src)]
    assert found == ["numpy", "p105cli.rules", "p105cli.kinematics.pairs"]
    assert [_subpackage(t) for t in found] == [None, "rules", "kinematics"]
    assert _subpackage("p105cli.__version__") == "__init__"

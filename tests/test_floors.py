"""The layout's one rule (DESIGN.md section 3): each floor imports only the floors below it or
its own, and no modules import each other in a circle. Read from the source (ast), so lazy
imports inside functions count too."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "occtrack"

FLOORS = {
    "cli": 7,
    "experiments": 6, "viz": 6, "integrations": 6,
    "peers": 5, "metrics": 5, "scenarios": 5, "baselines": 5,
    "tracker": 4,
    "filters": 3,
    "models": 2, "occlusion": 2, "association": 2,
    "densities": 1, "io": 1, "config": 1, "errors": 1, "progress": 1, "jit": 1, "exact": 1,
    "spatial": 1, "extras": 1, "_compat": 1,
}


def _modules() -> dict[str, Path]:
    out = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


MODULES = _modules()


def _imports(path: Path) -> set[str]:
    """The occtrack modules `path` imports, anywhere in it."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
        else:
            continue
        found.update(n for n in names if n in MODULES)
    return found


def _floor(module: str) -> int | None:
    parts = module.split(".")
    return FLOORS.get(parts[1]) if len(parts) > 1 else None


def test_every_module_has_a_floor():
    """A new top-level module or package gets a floor here (and in DESIGN.md) first."""
    homeless = [m for m in MODULES if m.count(".") >= 1 and _floor(m) is None
                and m != "occtrack.__main__"]
    assert homeless == []


@pytest.mark.parametrize("module", [m for m in MODULES if _floor(m) is not None])
def test_imports_only_its_floor_and_below(module):
    own = _floor(module)
    above = sorted(f"{m} (floor {_floor(m)})" for m in _imports(MODULES[module])
                   if _floor(m) is not None and _floor(m) > own)
    assert above == [], f"{module} (floor {own}) imports {above}"


def test_no_import_circles():
    """Between modules (a package's __init__ re-exporting its own modules is not a circle)."""
    graph = {m: {i for i in _imports(p) if i != m and not i.startswith(m + ".")
                 and not m.startswith(i + ".")}
             for m, p in MODULES.items()}
    state: dict[str, int] = {}
    circles = []

    def visit(m: str, path: list[str]) -> None:
        state[m] = 1
        for n in sorted(graph.get(m, ())):
            if state.get(n) == 1:
                circles.append(path[path.index(n):] + [n])
            elif n not in state:
                visit(n, path + [n])
        state[m] = 2

    for m in sorted(graph):
        if m not in state:
            visit(m, [m])
    assert circles == []

"""The layout shows the parts: emulator never imports bench, bench's packages import each other without cycles,
and every package says its role in its docstring."""

import ast
import importlib
import pkgutil
from pathlib import Path

import pytest

import bench

pytestmark = pytest.mark.unit
REPO = Path(__file__).resolve().parents[2]


def _imports(path: Path) -> set[str]:
    """Modules imported anywhere in ``path`` (top-level and inside functions)."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
    return names


def test_emulator_never_imports_bench():
    offenders = [str(p.relative_to(REPO)) for p in (REPO / "emulator").rglob("*.py")
                 if "tests" not in p.parts and any(n.split(".")[0] == "bench" for n in _imports(p))]
    assert offenders == []


def _package_of(module: str) -> str | None:
    parts = module.split(".")
    return parts[1] if parts[0] == "bench" and len(parts) > 2 else None


def test_bench_packages_have_no_import_cycles():
    """Edges between bench's subpackages (from any import, even deferred ones) form no cycle."""
    edges: dict[str, set[str]] = {}
    for path in (REPO / "bench").rglob("*.py"):
        rel = path.relative_to(REPO).with_suffix("")
        if "tests" in rel.parts or len(rel.parts) < 3:
            continue
        src = rel.parts[1]
        for name in _imports(path):
            dst = _package_of(name)
            if dst and dst != src and src not in ("cli", "pytest_plugin"):  # the CLI and plugin sit on top
                edges.setdefault(src, set()).add(dst)

    def reaches(a, b, seen=()):
        return any(n == b or (n not in seen and reaches(n, b, seen + (n,))) for n in edges.get(a, ()))

    cycles = sorted(a for a in edges if reaches(a, a))
    assert cycles == [], f"import cycles through: {cycles}; edges: {edges}"


def test_every_bench_package_states_its_role():
    for info in pkgutil.iter_modules(bench.__path__):
        if info.ispkg and info.name != "tests":
            doc = importlib.import_module(f"bench.{info.name}").__doc__
            assert doc and len(doc.split()) >= 8, f"bench.{info.name} has no role docstring"

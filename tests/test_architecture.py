"""The package layers of ``common`` (docs/architecture.md): each package imports only
the packages below it, and only ``common.bus`` (and the CLI) may touch Zenoh."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

COMMON = Path(__file__).resolve().parents[1] / "common"

# package -> the packages of common it may import (itself always allowed)
ALLOWED: dict[str, set[str]] = {
    "core": set(),
    "radar": {"core"},
    "sonar": {"core"},
    "evaluation": {"core", "radar", "sonar"},
    "deploy": {"core", "radar", "sonar"},
    "sim": {"core", "radar", "sonar", "deploy"},
    "wire": {"core", "radar", "sonar", "deploy"},
    "bus": {"core", "radar", "sonar", "deploy", "wire"},
}
PURE = {"core", "radar", "sonar", "evaluation", "sim"}
IO_MODULES = {"zenoh", "socket", "subprocess", "threading", "time", "asyncio"}
MAX_LINES = 400  # a longer module holds two jobs: split it (docs/architecture.md)


def _imports(path: Path) -> list[str]:
    """Every module name imported by ``path`` (absolute, as written)."""
    names = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names += [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.append(node.module)
            if node.module == "common":
                names += [f"common.{a.name}" for a in node.names]
    return names


def _modules() -> list[tuple[str, Path]]:
    return [(p.parent.name, p) for p in sorted(COMMON.glob("*/*.py"))]


def test_every_module_sits_in_a_known_package() -> None:
    assert {pkg for pkg, _ in _modules()} == set(ALLOWED)
    assert sorted(p.name for p in COMMON.glob("*.py")) == ["__init__.py", "__main__.py", "cli.py"]


def test_every_module_is_at_most_400_lines() -> None:
    sizes = {str(p.relative_to(COMMON.parent)): len(p.read_text().splitlines())
             for p in sorted(COMMON.rglob("*.py"))}
    assert len(sizes) > 40  # the walk found the package
    long = {p: n for p, n in sizes.items() if n > MAX_LINES}
    assert not long, f"modules over {MAX_LINES} lines (split them by job): {long}"


@pytest.mark.parametrize("pkg,path", _modules(), ids=lambda v: str(v).split("common/")[-1])
def test_imports_point_downwards(pkg: str, path: Path) -> None:
    for name in _imports(path):
        parts = name.split(".")
        if parts[0] == "services":
            pytest.fail(f"{path.name} imports a service: {name}")
        if parts[0] != "common":
            continue
        assert len(parts) > 1 and parts[1] != "cli", f"{path.name} imports {name}"
        target = parts[1]
        assert target == pkg or target in ALLOWED[pkg], (
            f"common/{pkg}/{path.name} imports {name}: {pkg} may import only {sorted(ALLOWED[pkg])}")


@pytest.mark.parametrize("pkg,path", [m for m in _modules() if m[0] in PURE],
                         ids=lambda v: str(v).split("common/")[-1])
def test_pure_packages_do_no_io(pkg: str, path: Path) -> None:
    bad = [n for n in _imports(path) if n.split(".")[0] in IO_MODULES]
    assert not bad, f"common/{pkg}/{path.name} imports {bad}: the core is driven by message time only"

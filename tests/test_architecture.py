"""The package layers of ``common`` (docs/architecture.md), at every depth: each role
package imports only the packages below it, each sub-package only the sub-packages
below it, no module circle anywhere, and only ``common.bus`` (and the CLI) may touch
Zenoh. The rules live in tests/architecture_rules.py; the planted trees below show that
each rule fails when broken."""

from __future__ import annotations

import ast
import textwrap
from pathlib import Path

import pytest

from tests.architecture_rules import ALLOWED, SUBLAYERS, cycles, layer_errors, modules

ROOT = Path(__file__).resolve().parents[1]
COMMON = ROOT / "common"
PURE = {"core", "radar", "sonar", "evaluation", "sim"}
IO_MODULES = {"zenoh", "socket", "subprocess", "threading", "time", "asyncio"}
MAX_LINES = 400  # a longer module holds two jobs: split it (docs/architecture.md)


def _raw_imports(path: Path) -> list[str]:
    names = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names += [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.append(node.module)
    return names


def _role_modules() -> list[tuple[str, Path]]:
    return [(p.relative_to(COMMON).parts[0], p) for p in sorted(COMMON.rglob("*.py"))
            if len(p.relative_to(COMMON).parts) > 1]


def test_every_module_sits_in_a_known_package() -> None:
    assert {pkg for pkg, _ in _role_modules()} == set(ALLOWED)
    assert sorted(p.name for p in COMMON.glob("*.py")) == ["__init__.py", "__main__.py", "cli.py"]
    for pkg, subs in SUBLAYERS.items():
        found = {d.name for d in (COMMON / pkg).iterdir() if d.is_dir() and (d / "__init__.py").exists()}
        assert found == set(subs), f"common/{pkg}: sub-packages {sorted(found)}, SUBLAYERS {subs}"
    deeper = [p for p in COMMON.rglob("*/") if p.is_dir() and p.name != "__pycache__"
              and not (p / "__init__.py").exists()]
    assert not deeper, f"folders of common without __init__.py: {deeper}"


def test_every_module_is_at_most_400_lines() -> None:
    sizes = {str(p.relative_to(ROOT)): len(p.read_text().splitlines()) for p in sorted(COMMON.rglob("*.py"))}
    assert len(sizes) > 40  # the walk found the package
    long = {p: n for p, n in sizes.items() if n > MAX_LINES}
    assert not long, f"modules over {MAX_LINES} lines (split them by job): {long}"


def test_the_walk_reaches_every_depth() -> None:
    names = set(modules(ROOT))
    assert "common.radar.fusion.cycle" in names and "common.sonar.mht.tracker" in names


def test_imports_point_downwards_at_every_depth() -> None:
    errors = layer_errors(ROOT)
    assert not errors, "upward imports:\n" + "\n".join(errors)


def test_no_import_circle_at_any_depth() -> None:
    found = cycles(ROOT)
    assert not found, f"import circles: {found}"


@pytest.mark.parametrize("pkg,path", [m for m in _role_modules() if m[0] in PURE],
                         ids=lambda v: str(v).split("common/")[-1])
def test_pure_packages_do_no_io(pkg: str, path: Path) -> None:
    bad = [n for n in _raw_imports(path) if n.split(".")[0] in IO_MODULES]
    assert not bad, f"{path.relative_to(ROOT)} imports {bad}: the core is driven by message time only"


def _plant(tmp_path: Path, files: dict[str, str]) -> Path:
    """A tree with ``common/<pkg>/__init__.py`` for every package and the given modules."""
    for rel, text in files.items():
        f = tmp_path / rel
        for d in [f.parent, *f.parent.parents]:
            if d == tmp_path:
                break
            d.mkdir(parents=True, exist_ok=True)
            (d / "__init__.py").touch()
        f.write_text(textwrap.dedent(text))
    return tmp_path


def test_planted_upward_import_three_levels_down_fails(tmp_path: Path) -> None:
    root = _plant(tmp_path, {"common/radar/fusion/deep/a.py": "from common.wire.protocol import x\n",
                             "common/wire/protocol.py": "x = 1\n"})
    assert any("radar may import only" in e for e in layer_errors(root))


def test_planted_upward_sub_package_import_fails(tmp_path: Path) -> None:
    root = _plant(tmp_path, {"common/sonar/bearing/model.py": "from common.sonar.mht import tracker\n",
                             "common/sonar/mht/tracker.py": "y = 1\n"})
    assert any("common.sonar.bearing may import only" in e for e in layer_errors(root))
    ok = _plant(tmp_path / "ok", {"common/sonar/mht/tracker.py": "from common.sonar.bearing import model\n",
                                  "common/sonar/bearing/model.py": "y = 1\n"})
    assert layer_errors(ok) == []


def test_planted_relative_and_service_imports_fail(tmp_path: Path) -> None:
    root = _plant(tmp_path, {"common/radar/plots/a.py": "from ..fusion import cycle\n",
                             "common/radar/fusion/cycle.py": "z = 1\n",
                             "common/core/b.py": "import services.global_fusion.main\n",
                             "common/core/c.py": "from common import cli\n"})
    errors = layer_errors(root)
    assert any("common.radar.plots.a imports common.radar.fusion.cycle" in e for e in errors)
    assert any("never imports a service" in e for e in errors)
    assert any("only services and the CLI" in e for e in errors)


def test_planted_circle_fails_even_behind_type_checking(tmp_path: Path) -> None:
    root = _plant(tmp_path, {
        "common/sonar/mht/a.py": "from common.sonar.mht.b import f\n",
        "common/sonar/mht/b.py": """
            from typing import TYPE_CHECKING
            if TYPE_CHECKING:
                from common.sonar.mht.c import g
            """,
        "common/sonar/mht/c.py": "from common.sonar.mht import a\n"})
    assert cycles(root) == [["common.sonar.mht.a", "common.sonar.mht.b", "common.sonar.mht.c"]]

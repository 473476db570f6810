"""The layer and cycle rules of ``common`` (docs/architecture.md), as functions over a
source tree so that tests/test_architecture.py can run them on the real tree and on
planted violations alike.

Every module at every depth is read. Three rules:
1. role packages (``common/<pkg>``) import only the packages below them (``ALLOWED``);
2. inside a role package, sub-packages import only the sub-packages listed before them
   in ``SUBLAYERS`` (a module directly in the role package sits above all of them);
3. no import circle between modules, at any depth, ``TYPE_CHECKING`` imports included.
"""

from __future__ import annotations

import ast
from pathlib import Path

# package -> the packages of common it may import (itself always allowed)
ALLOWED: dict[str, set[str]] = {
    "core": set(),
    "radar": {"core"},
    "sonar": {"core"},
    "evaluation": {"core", "radar", "sonar"},
    "deploy": {"core", "radar", "sonar"},
    "sim": {"core", "radar", "sonar", "deploy"},
    "wire": {"core", "radar", "sonar", "deploy", "sim"},
    "bus": {"core", "radar", "sonar", "deploy", "wire"},
}
# role package -> its sub-packages, lowest first: each may import those before it
SUBLAYERS: dict[str, list[str]] = {
    "radar": ["geometry", "plots", "elementary", "fusion", "network"],
    "sonar": ["bearing", "mht", "tma"],
}


def module_name(root: Path, path: Path) -> str:
    """Dotted name of ``path`` under ``root`` (the folder that holds ``common``)."""
    parts = list(path.relative_to(root).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def modules(root: Path) -> dict[str, Path]:
    """Every module of ``root/common``, at every depth, by dotted name."""
    return {module_name(root, p): p for p in sorted((root / "common").rglob("*.py"))}


def imports(root: Path, path: Path, known: set[str]) -> list[str]:
    """Every module that ``path`` imports, as written for absolute imports, resolved for
    relative ones; ``from pkg import mod`` names the module ``pkg.mod`` when it is one."""
    here = module_name(root, path).split(".")
    if path.name != "__init__.py":
        here = here[:-1]
    out: list[str] = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            out += [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = here[:len(here) - node.level + 1]
                base = ".".join(anchor + ([base] if base else []))
            for a in node.names:
                full = f"{base}.{a.name}"
                out.append(full if full in known else base)
    return out


def _upward(pkg: str, parts: list[str], t: list[str]) -> str | None:
    """Why the import of module ``t`` by module ``parts`` points upwards, or None."""
    if t[0] == "services":
        return "common never imports a service"
    if t[0] != "common":
        return None
    if len(t) < 2 or t[1] in ("cli", "__main__"):
        return "only services and the CLI sit above common"
    if t[1] != pkg:
        allowed = ALLOWED.get(pkg, set())
        return None if t[1] in allowed else f"{pkg} may import only {sorted(allowed)}"
    order = SUBLAYERS.get(pkg)
    if order is None or len(parts) < 4 or len(t) < 3 or t[2] == parts[2]:
        return None  # same sub-package, or a module directly in the role package
    mine = order.index(parts[2]) if parts[2] in order else -1
    if t[2] in order and order.index(t[2]) < mine:
        return None
    return f"common.{pkg}.{parts[2]} may import only {order[:max(mine, 0)]} of common.{pkg}"


def layer_errors(root: Path) -> list[str]:
    """Rules 1 and 2: every import that points upwards, names a service or the CLI."""
    mods = modules(root)
    errors = []
    for name, path in mods.items():
        parts = name.split(".")
        if len(parts) < 3:
            continue  # common/__init__, __main__ and cli sit above every package
        for target in imports(root, path, set(mods)):
            why = _upward(parts[1], parts, target.split("."))
            if why:
                errors.append(f"{name} imports {target}: {why}")
    return sorted(set(errors))


def cycles(root: Path) -> list[list[str]]:
    """Rule 3: the import circles between modules (strongly connected components of more
    than one module, or a module that imports itself), by Tarjan's algorithm."""
    mods = modules(root)
    graph = {m: sorted({t for t in imports(root, p, set(mods)) if t in mods and t != m
                        and not m.startswith(t + ".")}) for m, p in mods.items()}
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(sorted(comp))

    for m in graph:
        if m not in index:
            visit(m)
    return found

"""The one-form rules of issue 34, as functions over source text so that
tests/test_one_form.py can run them on the real tree and on planted violations alike.

Outside ``common/core`` no module may
1. wrap an angle by hand: ``%``, ``divmod``, ``np.mod``/``numpy.mod``, ``np.remainder``,
   ``np.fmod``, ``math.fmod`` with a full turn (2 pi written any way: ``2 * np.pi``,
   ``math.tau``, a ``TWO_PI``-like name, 6.2831...; or 360) as the other operand
   (``common.core.angles`` has the wraps);
2. write a quadratic form y' S^-1 y inline: a matmul chain ``a @ inv(S) @ a`` /
   ``a.T @ ... @ a`` / ``a @ solve(S, a)``, ``np.dot`` / ``.dot`` of the same, an
   einsum or an elementwise product over the same vector and an inverse (``inv``,
   ``pinv``, ``solve``, ``cho_solve``, ``solve_triangular``, or a name assigned from
   one in the same function) (``common.core.gating.quadratic_form`` is the one form).
A congruence ``A @ inv(S) @ A.T`` (a matrix, transposed last) is not a quadratic form.
"""

from __future__ import annotations

import ast
import math
from pathlib import Path

ROOTS = ("common", "services", "benchmarks")
EXEMPT = Path("common") / "core"
MOD_CALLS = {"mod", "remainder", "fmod"}
INVERSES = {"inv", "pinv", "solve", "cho_solve", "solve_triangular"}
TURN_NAMES = ("TWO_PI", "TWOPI", "TAU", "DOUBLE_PI")


def checked_files(root: Path) -> list[Path]:
    """Every .py file under ``ROOTS`` of ``root`` except those of ``common/core``."""
    return [p for r in ROOTS for p in sorted((root / r).rglob("*.py"))
            if not p.relative_to(root).is_relative_to(EXEMPT)]


def _name(node: ast.AST) -> str:
    """Last identifier of a Name or Attribute ('' otherwise)."""
    if isinstance(node, ast.Name):
        return node.id
    return node.attr if isinstance(node, ast.Attribute) else ""


def _is_pi(node: ast.AST) -> bool:
    return _name(node) == "pi"


def _is_turn(node: ast.AST) -> bool:
    """A full turn: 2 pi (any spelling) or 360."""
    if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) \
            and not isinstance(node.value, bool):
        return node.value == 360 or math.isclose(node.value, 2 * math.pi, rel_tol=1e-6)
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Mult):
        two = [isinstance(s, ast.Constant) and s.value == 2 for s in (node.left, node.right)]
        return (two[0] and _is_pi(node.right)) or (two[1] and _is_pi(node.left))
    name = _name(node).upper().lstrip("_")
    return any(name == t or name.startswith(t + "_") or name.endswith("_" + t) for t in TURN_NAMES)


def _call_name(node: ast.AST) -> str:
    return _name(node.func) if isinstance(node, ast.Call) else ""


def _wrap_errors(tree: ast.AST) -> list[tuple[int, str]]:
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Mod) and _is_turn(node.right):
            out.append((node.lineno, "angle wrap by %"))
        elif isinstance(node, ast.AugAssign) and isinstance(node.op, ast.Mod) and _is_turn(node.value):
            out.append((node.lineno, "angle wrap by %="))
        elif isinstance(node, ast.Call) and (_call_name(node) in MOD_CALLS | {"divmod"}) \
                and any(_is_turn(a) for a in node.args[1:2]):
            out.append((node.lineno, f"angle wrap by {_call_name(node)}"))
    return out


def _strip(node: ast.AST) -> ast.AST:
    """The vector under index views ([..., None], [..., 0]) and transposes (.T)."""
    while True:
        if isinstance(node, ast.Attribute) and node.attr == "T":
            node = node.value
        elif isinstance(node, ast.Subscript) and all(
                isinstance(e, (ast.Constant, ast.Slice)) for e in
                (node.slice.elts if isinstance(node.slice, ast.Tuple) else [node.slice])):
            node = node.value
        else:
            return node


class _Scope:
    """Names a function assigns from an inverse, with the right-hand side of a solve."""

    def __init__(self, func: ast.AST) -> None:
        self.inverse: dict[str, ast.AST | None] = {}
        for node in ast.walk(func):
            if isinstance(node, ast.Assign) and _inverse_calls(node.value):
                rhs = _solve_rhs(_strip(node.value))
                for t in node.targets:
                    if isinstance(t, ast.Name):
                        self.inverse[t.id] = rhs

    def has_inverse(self, node: ast.AST) -> bool:
        return bool(_inverse_calls(node)) or any(
            isinstance(n, ast.Name) and n.id in self.inverse for n in ast.walk(node))

    def vectors(self, operands: list[ast.AST]) -> list[str]:
        """Dumps of the operands and of the right-hand sides of the solves among them."""
        out = []
        for op in operands:
            op = _strip(op)
            out.append(ast.dump(op))
            rhs = _solve_rhs(op)
            if rhs is None and isinstance(op, ast.Name):
                rhs = self.inverse.get(op.id)
            if rhs is not None:
                out.append(ast.dump(rhs))
        return out


def _inverse_calls(node: ast.AST) -> list[ast.Call]:
    return [n for n in ast.walk(node) if isinstance(n, ast.Call) and _call_name(n) in INVERSES]


def _solve_rhs(node: ast.AST) -> ast.AST | None:
    """b of solve(S, b) (and its kin), stripped; None for anything else."""
    if isinstance(node, ast.Call) and _call_name(node) in INVERSES - {"inv", "pinv"} \
            and len(node.args) >= 2:
        return _strip(node.args[1])
    return None


def _chain(node: ast.AST) -> list[ast.AST]:
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.MatMult):
        return _chain(node.left) + _chain(node.right)
    return [node]


def _form_errors(tree: ast.AST) -> list[tuple[int, str]]:
    out = []
    funcs = [n for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))]
    scopes = [(f, _Scope(f)) for f in funcs] + [(tree, _Scope(ast.Module(body=[], type_ignores=[])))]
    seen: set[int] = set()
    for root, scope in scopes:
        for node in ast.walk(root):
            if id(node) in seen:
                continue
            operands, what = _operands(node)
            if len(operands) < 2 or not scope.has_inverse(node):
                continue
            vec = scope.vectors(operands)
            if len(set(vec)) < len(vec):
                seen.add(id(node))
                out.append((node.lineno, f"inline quadratic form ({what})"))
    return out


def _operands(node: ast.AST) -> tuple[list[ast.AST], str]:
    """The operands of a product node that could be y' S^-1 y, and its kind."""
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.MatMult):
        ops = _chain(node)
        if len(ops) > 2 and isinstance(ops[-1], ast.Attribute) and ops[-1].attr == "T":
            return [], ""  # A X A': a congruence, not a form
        return ops, "@"
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Mult):
        return [node.left, node.right], "*"
    name = _call_name(node)
    if isinstance(node, ast.Call) and name == "einsum":
        return list(node.args[1:]), "einsum"
    if isinstance(node, ast.Call) and name in ("dot", "vdot", "inner"):
        func = node.func
        own = [func.value] if isinstance(func, ast.Attribute) and _name(func.value) not in ("np", "numpy") else []
        return own + list(node.args), name
    return [], ""


def errors(source: str) -> list[tuple[int, str]]:
    """(line, what) of every hand-written angle wrap and inline quadratic form."""
    tree = ast.parse(source)
    return sorted(_wrap_errors(tree) + _form_errors(tree))

"""Issue 34: one angle wrap (common.core.angles) and one quadratic form
(common.core.gating.quadratic_form) outside common/core, by the rules of
tests/form_rules.py, on the real tree and on planted violations."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from tests.form_rules import checked_files, errors

ROOT = Path(__file__).resolve().parents[1]


def test_the_walk_covers_common_services_and_benchmarks_but_not_core() -> None:
    rel = {p.relative_to(ROOT).as_posix() for p in checked_files(ROOT)}
    assert "common/sonar/mht/tracker.py" in rel and "services/evaluate/main.py" in rel
    assert "benchmarks/mht.py" in rel and not any(r.startswith("common/core/") for r in rel)


def test_no_hand_written_wrap_or_quadratic_form_outside_core() -> None:
    found = [f"{p.relative_to(ROOT)}:{line}: {what}"
             for p in checked_files(ROOT) for line, what in errors(p.read_text())]
    assert not found, "\n".join(found)


WRAPS = [
    "w = np.mod(a, 2 * np.pi)",
    "w = numpy.mod(a, 2.0 * numpy.pi)",
    "w = np.remainder(a, TWO_PI)",
    "w = np.fmod(a, math.tau)",
    "w = math.fmod(a, 2 * math.pi)",
    "w = a % (2 * np.pi)",
    "w = a % (np.pi * 2)",
    "w = (a + b) % TWO_PI",
    "w = a % _TWO_PI",
    "w = a % twopi",
    "w = a % math.tau",
    "w = a % np.tau",
    "w = a % 6.283185307179586",
    "w = a % 360",
    "w = np.mod(a, 360.0)",
    "a %= 2 * pi",
    "q, w = divmod(a, 2 * math.pi)",
]
FORMS = [
    "d2 = y @ np.linalg.inv(S) @ y",
    "d2 = y.T @ inv(S) @ y",
    "d2 = y @ np.linalg.solve(S, y)",
    "d2 = np.dot(y, np.linalg.solve(S, y))",
    "d2 = y.dot(scipy.linalg.solve(S, y))",
    'd2 = np.einsum("ki,ki->k", y, np.linalg.solve(S, y[..., None])[..., 0])',
    'd2 = np.einsum("...i,...ij,...j->...", y, np.linalg.inv(S), y)',
    "d2 = (y * np.linalg.solve(S, y[..., None])[..., 0]).sum(-1)",
    "def f(y, S):\n    Si = np.linalg.inv(S)\n    return np.einsum('ni,nij,nj->n', y, Si, y)",
    "def f(y, S):\n    x = np.linalg.solve(S, y)\n    return y @ x",
    "def f(y, L):\n    u = solve_triangular(L, y, lower=True)\n    return u @ u",
    "def f(y, c):\n    return np.einsum('ki,ki->k', y, cho_solve(c, y.T).T)",
]
ALLOWED = [
    "w = wrap_2pi(a)",
    "w = wrap_pi(a + np.pi)",
    "w = a % 2",
    "w = np.mod(k, n)",
    "w = a % (np.pi / 2)",
    "d2 = quadratic_form(y, S)",
    "P = F @ np.linalg.inv(J) @ F.T",
    "S = H @ P @ H.T + R",
    "K = np.linalg.solve(S, H @ P).T",
    "x = np.linalg.solve(A, b)",
    'c = np.einsum("pki,pk,pkj->pij", A, w, A)',
    'x = np.einsum("pij,pkj,pk->pi", np.linalg.inv(M), A, v)',
    'e = np.einsum("ni,ni->n", e, (J0 @ e[..., None])[..., 0])',
    "def f(y, S):\n    Si = np.linalg.inv(S)\n    return Si @ y",
]


@pytest.mark.parametrize("src", WRAPS)
def test_planted_wrap_is_found(src: str) -> None:
    assert [w for _, w in errors(src)] and all("wrap" in w for _, w in errors(src))


@pytest.mark.parametrize("src", FORMS)
def test_planted_quadratic_form_is_found(src: str) -> None:
    assert any("quadratic form" in w for _, w in errors(src))


@pytest.mark.parametrize("src", ALLOWED)
def test_allowed_code_passes(src: str) -> None:
    assert errors(src) == []


def test_lines_are_reported() -> None:
    src = textwrap.dedent("""\
        import numpy as np

        def f(y, S, a):
            b = a % (2 * np.pi)
            return b, y @ np.linalg.solve(S, y)
        """)
    assert [line for line, _ in errors(src)] == [4, 5]

"""Unit tests of the IMM steps (common.core.imm; Bar-Shalom, Li, Kirubarajan 11.6.6)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.linalg import expm
from scipy.stats import multivariate_normal

from common.core import imm


@pytest.mark.parametrize("tau", [[60.0, 10.0], [30.0, 5.0, 12.0]])
def test_transition_is_the_matrix_exponential_of_the_generator(tau: list[float]) -> None:
    tau = np.array(tau)
    M = tau.size
    G = np.tile((1.0 / tau / (M - 1))[:, None], (1, M))
    G[np.arange(M), np.arange(M)] = -1.0 / tau
    dt = np.array([0.0, 1.0, 7.5])
    p = imm.transition(dt, tau)
    np.testing.assert_allclose(p.sum(axis=2), 1.0)
    for k in range(dt.size):
        np.testing.assert_allclose(p[k], expm(G * dt[k]), atol=1e-12)


def test_one_model_never_leaves() -> None:
    """M = 1 (the seed's single EKF, [radar.fusion] filter = "seed"): p = 1 at every step,
    not exp(-dt / tau), which would shrink the weight of the only model."""
    p = imm.transition(np.array([0.0, 1.0, 50.0]), np.array([60.0]))
    np.testing.assert_array_equal(p, np.ones((3, 1, 1)))


def test_stationary_distribution_is_kept_by_the_chain() -> None:
    tau = np.array([60.0, 10.0])
    pi = tau / tau.sum()
    p = imm.transition(np.array([3.0]), tau)[0]
    np.testing.assert_allclose(pi @ p, pi)


def test_mixing_with_no_transition_keeps_the_models() -> None:
    rng = np.random.default_rng(1)
    xm = rng.normal(size=(4, 2, 6))
    A = rng.normal(size=(4, 2, 6, 6))
    Pm = A @ np.swapaxes(A, 2, 3) + np.eye(6)
    mu = np.array([[0.3, 0.7]] * 4)
    c, x0, P0 = imm.mix(mu, xm, Pm, np.tile(np.eye(2), (4, 1, 1)))
    np.testing.assert_allclose(c, mu)
    np.testing.assert_allclose(x0, xm)
    np.testing.assert_allclose(P0, Pm)


def test_mixing_equals_the_textbook_sums() -> None:
    """11.6.6-6 to -9 written out for one track, against the vectorised step."""
    rng = np.random.default_rng(2)
    xm = rng.normal(size=(1, 2, 3))
    Pm = np.stack([np.eye(3) * 2.0, np.eye(3) * 0.5])[None]
    mu = np.array([[0.8, 0.2]])
    p = np.array([[[0.95, 0.05], [0.3, 0.7]]])
    c, x0, P0 = imm.mix(mu, xm, Pm, p)
    for j in range(2):
        cj = sum(p[0, i, j] * mu[0, i] for i in range(2))
        w = [p[0, i, j] * mu[0, i] / cj for i in range(2)]
        xj = sum(w[i] * xm[0, i] for i in range(2))
        Pj = sum(w[i] * (Pm[0, i] + np.outer(xm[0, i] - xj, xm[0, i] - xj)) for i in range(2))
        assert c[0, j] == pytest.approx(cj)
        np.testing.assert_allclose(x0[0, j], xj)
        np.testing.assert_allclose(P0[0, j], Pj)


@settings(max_examples=50, deadline=None)
@given(st.floats(0.01, 0.99), st.floats(-10, 10), st.floats(-10, 10),
       st.floats(0.1, 5.0), st.floats(0.1, 5.0))
def test_combination_is_the_mixture_moments(w: float, m1: float, m2: float, s1: float,
                                            s2: float) -> None:
    mu = np.array([[w, 1.0 - w]])
    xm = np.array([[[m1], [m2]]])
    Pm = np.array([[[[s1**2]], [[s2**2]]]])
    x, P = imm.combine(mu, xm, Pm)
    mean = w * m1 + (1 - w) * m2
    second = w * (s1**2 + m1**2) + (1 - w) * (s2**2 + m2**2)
    assert x[0, 0] == pytest.approx(mean)
    assert P[0, 0, 0] == pytest.approx(second - mean**2, rel=1e-9, abs=1e-9)


def test_probabilities_are_bayes_rule_and_survive_tiny_likelihoods() -> None:
    c = np.array([[0.9, 0.1], [0.5, 0.5]])
    ll = np.array([[np.log(0.2), np.log(0.6)], [-20000.0, -20003.0]])
    mu = imm.probabilities(c, ll)
    assert mu[0, 0] == pytest.approx(0.18 / (0.18 + 0.06))
    assert mu[1, 1] == pytest.approx(np.exp(-3.0) / (1.0 + np.exp(-3.0)))
    np.testing.assert_allclose(imm.probabilities(c, np.zeros((2, 2))), c)


def test_gaussian_loglik_is_the_normal_log_density() -> None:
    rng = np.random.default_rng(3)
    A = rng.normal(size=(5, 4, 4))
    S = A @ np.swapaxes(A, 1, 2) + np.eye(4)
    nu = rng.normal(size=(5, 4))
    nis = np.einsum("ni,ni->n", nu, np.linalg.solve(S, nu[..., None])[..., 0])
    ref = [multivariate_normal(np.zeros(4), S[k]).logpdf(nu[k]) for k in range(5)]
    np.testing.assert_allclose(imm.gaussian_loglik(nis, S), ref)

"""Module 65 of 001: EKF of the global tracks, state [x vx y vy z vz].

Prediction with F and Q of [51] (common.core.motion.cv_F / cv_Q), [55]-[56].
Observation [49] y = [x_f y_f z_f v_b^1 ... v_b^n] with covariance [50] (the block
covariance of module 64 and the contributing bases' sigma_vb^2), model h of
[53]-[54] and its Jacobian [57]; update [58]-[62] by common.core.kalman.ekf_update
(Joseph form; gain_scale = alpha of seed 004).

Variable dimension, vectorised: every track gets a vector of fixed size 3 + B (B the
number of configured bases); the row of a base that does not contribute has H = 0,
innovation 0 and unit variance, which adds no information, so the update equals the
update with the contributing rows only (the seed's 3 + nb_cet).

Deviation (stated): a track with exactly one contributing updated elementary track
cannot be localised (one ellipsoid); it is updated with that track's [r_b, v_b, theta]
through g of [47] (`single_base_update`) instead of skipping the update.
"""

from __future__ import annotations

import numpy as np

from common.core import kalman
from common.core.gating import quadratic_form
from common.core.imm import gaussian_loglik
from common.core.motion import cv_F, cv_Q
from common.radar.geometry.bistatic import POS, project, project_jacobian


def predict(x: np.ndarray, P: np.ndarray, dt: np.ndarray, q: np.ndarray | float, q_z: float):
    """001 [55]-[56] with per-track time steps dt (N,) and noise powers q (N,) or scalar."""
    return kalman.predict(x, P, cv_F(dt), cv_Q(dt, q, q_z))


def observation(x: np.ndarray, tx: np.ndarray, rx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """h of 001 [53]-[54] for every base (N, 3 + B) and its Jacobian [57] (N, 3 + B, 6).

    Rows 0-2: the position (x, y, z); row 3 + b: v_b of base b ([2], i.e. the second
    component of g [47]) with d v_b / d state from common.radar.geometry.bistatic.project_jacobian.
    """
    n, B = x.shape[0], tx.shape[0]
    h = np.zeros((n, 3 + B))
    H = np.zeros((n, 3 + B, 6))
    h[:, :3] = x[:, POS]  # 001 [54], position rows
    H[:, [0, 1, 2], POS] = 1.0
    xs, txs, rxs = np.repeat(x, B, axis=0), np.tile(tx, (n, 1)), np.tile(rx, (n, 1))
    h[:, 3:] = project(xs, txs, rxs)[:, 1].reshape(n, B)  # 001 [54], all bases at once
    H[:, 3:] = project_jacobian(xs, txs, rxs)[:, 1].reshape(n, B, 6)  # 001 [57]
    return h, H


def _innovation(x: np.ndarray, pos: np.ndarray, pos_cov: np.ndarray, vb: np.ndarray,
                vb_var: np.ndarray, active: np.ndarray, tx: np.ndarray, rx: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Innovation y - h of [49] (N, 3 + B), Jacobian [57] and R of [50]; an inactive v_b
    row is padded (innovation 0, H row 0, variance 1)."""
    n, B = vb.shape
    h, H = observation(x, tx, rx)
    nu = np.concatenate([pos - h[:, :3], np.where(active, vb - h[:, 3:], 0.0)], axis=1)  # [49]
    H[:, 3:] *= active[..., None]
    R = np.zeros((n, 3 + B, 3 + B))
    R[:, :3, :3] = pos_cov
    R[:, np.arange(3, 3 + B), np.arange(3, 3 + B)] = np.where(active, vb_var, 1.0)  # [50]
    return nu, H, R


def fused_update(
    x: np.ndarray, P: np.ndarray, pos: np.ndarray, pos_cov: np.ndarray, vb: np.ndarray,
    vb_var: np.ndarray, active: np.ndarray, tx: np.ndarray, rx: np.ndarray,
    gain_scale: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """EKF update [58]-[62] with y of [49] and R of [50]; returns (x, P, log-likelihood
    (N,) of the measurement, common.core.imm.gaussian_loglik of [58]'s innovation).

    pos (N, 3), pos_cov (N, 3, 3) from module 64; vb, vb_var, active (N, B).
    """
    nu, H, R = _innovation(x, pos, pos_cov, vb, vb_var, active, tx, rx)
    x_new, P_new, loglik = _update(x, P, nu, H, R, gain_scale)
    # a padded row (S = 1, innovation 0) adds log N(0; 0, 1): removed, so that loglik is
    # that of the contributing rows only (3 + nb_cet dimensions)
    return x_new, P_new, loglik + 0.5 * np.log(2.0 * np.pi) * (~active).sum(axis=1)


def vb_deletion_residuals(
    x: np.ndarray, P: np.ndarray, pos: np.ndarray, pos_cov: np.ndarray, vb: np.ndarray,
    vb_var: np.ndarray, active: np.ndarray, tx: np.ndarray, rx: np.ndarray,
) -> np.ndarray:
    """Leave-one-out test of the v_b rows of y [49] (arguments of `fused_update`):
    r_j^2 = (S^-1 nu)_j^2 / (S^-1)_jj (N, B), the squared innovation of row j against
    the prediction updated with all the other rows of [49], in its own sigma (chi-square,
    1 dof, when the rows belong to the track's target); 0 where not active."""
    nu, H, R = _innovation(x, pos, pos_cov, vb, vb_var, active, tx, rx)
    W = np.linalg.inv(H @ P @ np.swapaxes(H, 1, 2) + R)
    u = (W @ nu[..., None])[..., 0]
    return np.where(active, u[:, 3:] ** 2 / np.diagonal(W, axis1=1, axis2=2)[:, 3:], 0.0)


def single_base_update(
    x: np.ndarray, P: np.ndarray, y: np.ndarray, R: np.ndarray, tx: np.ndarray, rx: np.ndarray,
    gain_scale: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """EKF update with one base's [r_b, v_b, theta] (N, 3), R (N, 3, 3) through g [47]
    (tx, rx (N, 3) per track); the azimuth innovation is wrapped. Returns (x, P,
    log-likelihood (N,))."""
    nu = kalman.innovation(y, project(x, tx, rx), angle_idx=[2])
    return _update(x, P, nu, project_jacobian(x, tx, rx), R, gain_scale)


def _update(x: np.ndarray, P: np.ndarray, nu: np.ndarray, H: np.ndarray, R: np.ndarray,
            gain_scale: np.ndarray | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """[58]-[62] on innovation nu, and the Gaussian log-likelihood of nu."""
    x_new, P_new, S, _ = kalman.update(x, P, nu, H, R, gain_scale=gain_scale)
    nis = quadratic_form(nu, S)
    return x_new, P_new, gaussian_loglik(nis, S)

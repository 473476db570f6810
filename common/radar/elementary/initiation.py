"""Module 42 of seed 001 (step 23): elementary track initialisation from two successive
fused plots p_{k-1}, p_k not associated to any maintained track.

Propagation of p_{k-1} to t_k (001 [13]-[14]), compatibility test (001 [15]) with a
wide window Delta_vb on v_b, initial state and covariance (001 [16]-[17]). Every
compatible pair opens a track, so several tracks may start from one plot.

A range-Doppler base's plots have no theta: the same equations without their theta
rows (y~ = [r~, v~], x = [r_b, v_b, gamma_b], P 3x3).
"""

from __future__ import annotations

import numpy as np

from common.core.angles import wrap_2pi, wrap_pi
from common.core.gating import window_pairs
from common.radar.plots.channel_fusion import Plots


def propagate(prev: Plots, dt: float, sigma_gamma: float, sigma_omega: float
              ) -> tuple[np.ndarray, np.ndarray]:
    """Plots of t_{k-1} propagated by dt = t_k - t_{k-1}: (y~ (N, 3), sigma~ (N, 3)).

    001 [13]: r~ = r + v dt, v~ = v, theta~ = theta (the seed prints theta~ on the right
    of the third line, read as theta^{p,k-1}). 001 [14]: sigma_gamma and sigma_omega are
    the model noise constants sigma_v~ and sigma_omega of the seed, the ones of Q [20].
    Without azimuth: (N, 2), the first two columns.
    """
    y = [prev.rb + prev.vb * dt, prev.vb]  # 001 [13]
    s = [
        np.sqrt(prev.srb**2 + dt**2 * prev.svb**2 + dt**5 * sigma_gamma**2 / 20.0),  # 001 [14]
        np.sqrt(prev.svb**2 + dt**3 * sigma_gamma**2 / 3.0),
    ]
    if prev.az is not None and prev.saz is not None:
        y.append(prev.az)
        s.append(np.sqrt(prev.saz**2 + dt**3 * sigma_omega**2 / 3.0))
    return np.column_stack(y), np.column_stack(s)


def compatible(y_prop: np.ndarray, s_prop: np.ndarray, cur: Plots, delta_vb: float
               ) -> tuple[np.ndarray, np.ndarray]:
    """Compatible pairs (i of the propagated plots, j of cur) by 001 [15]:
    |r - r~| <= 3 (s_r + s_r~), |v - v~| <= Delta_vb, |theta - theta~| <= 3 (s_th + s_th~)
    (azimuth difference on the circle; the first two tests alone without azimuth).
    Candidates come from a sweep on r_b."""
    if y_prop.shape[0] == 0 or len(cur) == 0:
        e = np.zeros(0, dtype=np.intp)
        return e, e
    half = 3.0 * (s_prop[:, 0] + cur.srb.max())
    i, j = window_pairs(y_prop[:, 0] - half, y_prop[:, 0] + half, cur.rb)
    ok = (
        (np.abs(cur.rb[j] - y_prop[i, 0]) <= 3.0 * (cur.srb[j] + s_prop[i, 0]))  # 001 [15]
        & (np.abs(cur.vb[j] - y_prop[i, 1]) <= delta_vb)
    )
    if cur.az is not None and cur.saz is not None:
        ok &= np.abs(wrap_pi(cur.az[j] - y_prop[i, 2])) <= 3.0 * (cur.saz[j] + s_prop[i, 2])
    return i[ok], j[ok]


def initial_state(prev: Plots, cur: Plots, i: np.ndarray, j: np.ndarray, dt: float,
                  sigma_gamma_init: float, sigma_omega_init: float
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Initial state x (K, 5) and covariance P (K, 5, 5) of the tracks opened by the
    pairs (prev[i], cur[j]).

    001 [16]: x = [r_b^k, v_b^k, (v_b^k - v_b^{k-1}) / dt, theta^k,
    (theta^k - theta^{k-1}) / dt] (the seed's left-hand side omits gamma_b; the right-hand
    side has the five components); azimuth difference on the circle.
    001 [17]: P = diag(s_rb^2, s_vb^2, sigma_gamma_init^2, s_theta^2, sigma_omega_init^2).
    Without azimuth: x (K, 3) and P (K, 3, 3), the first three components.
    """
    x = [cur.rb[j], cur.vb[j], (cur.vb[j] - prev.vb[i]) / dt]  # 001 [16]
    d = [cur.srb[j] ** 2, cur.svb[j] ** 2, np.full(j.size, sigma_gamma_init**2)]  # 001 [17]
    if cur.az is not None and cur.saz is not None and prev.az is not None:
        x += [wrap_2pi(cur.az[j]), wrap_pi(cur.az[j] - prev.az[i]) / dt]
        d += [cur.saz[j] ** 2, np.full(j.size, sigma_omega_init**2)]
    n = len(x)
    P = np.zeros((j.size, n, n))
    P[:, range(n), range(n)] = np.column_stack(d)
    return np.column_stack(x), P

"""Resolution conflicts of the multiple-hypothesis embodiment of seed 000 (broadband).

Two confirmed tracks i, j whose main hypotheses processed the same measurement are in
conflict (IN_i = j). While the conflict lasts, the children of their main hypotheses are
re-weighted and modified by the joint interpretations (1)-(5) of 000:
  (1) unresolved and detected: the group measurement z_l and the fictitious measurement
      "separation = 0" update the joint state; p1 = P_u P_D^u / f_c p(z_l | unresolved);
  (2) unresolved, not detected: the fictitious measurement only; p2 = P_u (1 - P_D^u);
  (3) resolved, both detected by z_l1 != z_l2: p3 = (1 - P_u) P_D^1 P_D^2 / f_c^2 N1 N2;
  (4) resolved, one detected: p4 = (1 - P_u) (1 - P_D^2) P_D^1 / f_c N1 (and 1 <-> 2);
  (5) resolved, none detected: p5 = (1 - P_u) (1 - P_D^1) (1 - P_D^2).
The unresolved measurement is predicted from the two targets' states by the unscented
transform: h_u(x_1, x_2) = [theta_1 - theta_2, theta_1 + (theta_2 - theta_1) / 2, a_u].
Joint hypotheses go back to single-target ones at once by moment matching: the children
of track i with the same key (missed, or measurement l) are the mixture of the joint
hypotheses that give track i that key.

Deviations (stated):
- The third component of 000's unresolved state is printed (a_i - a_j) / 2; a measured
  level of two unresolved sources is their power sum, a_u = 10 log10(10^(a_1/10) +
  10^(a_2/10)) (dB), a nonlinear function (the reason for the unscented transform).
- P_u, "a function of the sensor's resolution and the separation", is
  exp(-(theta_1 - theta_2)^2 / (2 res^2)) at the predicted separation; the fictitious
  measurement "separation = 0" has standard deviation res.
- P_D^u is the erfc law of 000 at the predicted group level a_u and its UT sigma.
- Normalisation: the children of each main hypothesis keep their total weight (its
  single-target evidence); the joint interpretation re-distributes it among them.
- Only the two main hypotheses take part (not every combination of hypotheses).
"""

from __future__ import annotations

import math

import numpy as np

from common.core.angles import wrap_2pi, wrap_pi
from common.core.gating import quadratic_form
from common.sonar.bearing.model import detection_probability

LN_2PI = math.log(2.0 * math.pi)
BRG, AMP = 0, 2  # state indices of bearing and amplitude level


def unresolved_probability(dtheta: float, res: float) -> float:
    """P_u = exp(-dtheta^2 / (2 res^2)) (see the module docstring)."""
    return math.exp(-0.5 * (wrap_pi(dtheta) / res) ** 2)


def h_unresolved(X: np.ndarray, n: int) -> np.ndarray:
    """000 unresolved measurement of joint states X (..., 2n): separation, centre,
    group level (power sum, dB)."""
    t1, t2 = X[..., BRG], X[..., n + BRG]
    a1, a2 = X[..., AMP], X[..., n + AMP]
    sep = wrap_pi(t1 - t2)  # 000 y^u_1 = theta_i - theta_j
    centre = wrap_2pi(t1 + 0.5 * wrap_pi(t2 - t1))  # 000 y^u_2
    level = 10.0 * np.log10(10.0 ** (a1 / 10.0) + 10.0 ** (a2 / 10.0))
    return np.stack([sep, centre, level], axis=-1)


def unscented(X: np.ndarray, P: np.ndarray, n: int, kappa: float = 0.0) -> tuple[
        np.ndarray, np.ndarray, np.ndarray]:
    """Unscented transform of h_unresolved at joint mean X (2n,), covariance P:
    predicted measurement, its covariance P_zz and the cross covariance P_xz.
    Sigma points X +- sqrt((N + kappa) P) columns, weights kappa/(N+kappa), 1/(2(N+kappa));
    kappa = 3 - N is the usual choice, kappa = 0 keeps all weights positive."""
    N = X.size
    L = np.linalg.cholesky((N + kappa) * P)
    pts = np.vstack([X, X + L.T, X - L.T])
    w = np.r_[kappa / (N + kappa), np.full(2 * N, 0.5 / (N + kappa))]
    Z = h_unresolved(pts, n)
    z0 = Z[0]
    dz = Z - z0
    dz[:, :2] = wrap_pi(dz[:, :2])
    zm = z0 + w @ dz
    zm[:2] = [wrap_pi(zm[0]), wrap_2pi(zm[1])]
    e = dz - (zm - z0)
    e[:, :2] = wrap_pi(e[:, :2])
    dx = pts - X
    return zm, (w * e.T) @ e, (w * dx.T) @ e


def joint_update(X: np.ndarray, P: np.ndarray, zm: np.ndarray, Pzz: np.ndarray,
                 Pxz: np.ndarray, z: np.ndarray, R: np.ndarray, rows: list[int]
                 ) -> tuple[np.ndarray, np.ndarray, float]:
    """Kalman update of the joint state with the components `rows` of the unresolved
    measurement z (separation 0 = fictitious, centre, level); returns X+, P+ and the
    log density of the measured components except the fictitious one."""
    S = Pzz[np.ix_(rows, rows)] + R[np.ix_(rows, rows)]
    y = z[rows] - zm[rows]
    y[: min(2, len(rows))] = wrap_pi(y[: min(2, len(rows))])
    K = np.linalg.solve(S, Pxz[:, rows].T).T
    Xn = X + K @ y
    Pn = P - K @ S @ K.T
    meas = [i for i, r in enumerate(rows) if r != 0]
    logp = 0.0
    if meas:
        Sm, ym = S[np.ix_(meas, meas)], y[meas]
        logp = -0.5 * (quadratic_form(ym, Sm) + len(meas) * LN_2PI
                       + math.log(np.linalg.det(Sm)))
    return Xn, 0.5 * (Pn + Pn.T), logp


def interpret(
    pred: tuple[tuple[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]],
    hits: tuple[dict[int, tuple[np.ndarray, np.ndarray, float]], dict[int, tuple[np.ndarray, np.ndarray, float]]],
    p_d: tuple[float, float], z: np.ndarray, Rd: np.ndarray, rho_f: float, res: float,
    p_d_max: float, d_thr: float,
) -> list[dict[int, tuple[np.ndarray, np.ndarray, float]]]:
    """The joint interpretations (1)-(5) of one conflicting pair, reduced to single-target
    children by moment matching. pred: predicted (x, P) of the two main hypotheses;
    hits[r]: measurement index l -> (x_upd, P_upd, log N_r(z_l)) of track r's children;
    z (M, 2) measurements [brg, level], Rd (M, 2) their variances. Returns per track a
    dict key -> (x, P, probability): key -1 the missed detection, l a measurement; the
    probabilities of both tracks sum to one over all joint hypotheses."""
    (x1, P1), (x2, P2) = pred
    n = x1.size
    pu = unresolved_probability(x1[BRG] - x2[BRG], res)
    comps: list[list[tuple[int, np.ndarray, np.ndarray, float]]] = [[], []]  # key, x, P, p

    def add(k1: int, s1: tuple[np.ndarray, np.ndarray], k2: int,
            s2: tuple[np.ndarray, np.ndarray], p: float) -> None:
        comps[0].append((k1, s1[0], s1[1], p))
        comps[1].append((k2, s2[0], s2[1], p))

    pd1, pd2 = p_d
    add(-1, (x1, P1), -1, (x2, P2), (1 - pu) * (1 - pd1) * (1 - pd2))  # 000 p5
    for l, (xu, Pu_, lg) in hits[0].items():  # 000 p4, target 1 detected
        add(l, (xu, Pu_), -1, (x2, P2), (1 - pu) * (1 - pd2) * pd1 * math.exp(lg) / rho_f)
    for l, (xu, Pu_, lg) in hits[1].items():  # 000 p4, target 2 detected
        add(-1, (x1, P1), l, (xu, Pu_), (1 - pu) * (1 - pd1) * pd2 * math.exp(lg) / rho_f)
    for l1, (xa, Pa, la) in hits[0].items():  # 000 p3
        for l2, (xb, Pb, lb) in hits[1].items():
            if l1 != l2:
                add(l1, (xa, Pa), l2, (xb, Pb),
                    (1 - pu) * pd1 * pd2 * math.exp(la + lb) / rho_f**2)
    if pu > 1e-6:
        X = np.r_[x1, x2]
        P = np.zeros((2 * n, 2 * n))
        P[:n, :n], P[n:, n:] = P1, P2
        zm, Pzz, Pxz = unscented(X, P, n)
        pdu = float(detection_probability(zm[2], math.sqrt(max(Pzz[2, 2], 1e-12)), p_d_max, d_thr))
        for l in sorted(set(hits[0]) | set(hits[1])):  # 000 p1
            R = np.diag([res**2, Rd[l, 0], Rd[l, 1]])
            Xn, Pn, lg = joint_update(X, P, zm, Pzz, Pxz, np.r_[0.0, z[l]], R, [0, 1, 2])
            add(l, (Xn[:n], Pn[:n, :n]), l, (Xn[n:], Pn[n:, n:]), pu * pdu * math.exp(lg) / rho_f)
        R = np.diag([res**2, 1.0, 1.0])
        Xn, Pn, _ = joint_update(X, P, zm, Pzz, Pxz, np.zeros(3), R, [0])  # 000 p2
        add(-1, (Xn[:n], Pn[:n, :n]), -1, (Xn[n:], Pn[n:, n:]), pu * (1 - pdu))
    total = sum(c[3] for c in comps[0])
    return [_moment_match(c, total) for c in comps]


def _moment_match(comps: list[tuple[int, np.ndarray, np.ndarray, float]], total: float
                  ) -> dict[int, tuple[np.ndarray, np.ndarray, float]]:
    """Second-order moment matching of the joint components per key (000: p(x_1) =
    integral p(x_1, x_2) dx_2)."""
    out: dict[int, tuple[np.ndarray, np.ndarray, float]] = {}
    for key in sorted({c[0] for c in comps}):
        sel = [c for c in comps if c[0] == key]
        w = np.array([c[3] for c in sel])
        s = w.sum()
        if s <= 0.0:
            continue
        xs = np.array([c[1] for c in sel])
        ref = xs[int(np.argmax(w))]
        d = xs - ref
        d[:, BRG] = wrap_pi(d[:, BRG])
        xm = ref + (w / s) @ d
        e = d - (xm - ref)
        Pm = sum(wi / s * (c[2] + np.outer(ei, ei)) for wi, c, ei in zip(w, sel, e))
        xm[BRG] = wrap_2pi(xm[BRG])
        out[key] = (xm, Pm, s / total)
    return out


def relink_choice(omega_rate: float, omega_amp: float, rate_i: float, rate_j: float,
                  amp_i: float, amp_j: float) -> int:
    """000 end of a conflict when a new confirmed track omega is near hypotheses of both
    conflicting tracks: 0 to link omega to track i, 1 to track j. The one whose bearing
    rate from before the conflict has the sign of omega's rate; if both (or neither) do,
    the one whose amplitude from before the conflict is nearer omega's (ties: i)."""
    si = math.copysign(1.0, rate_i) == math.copysign(1.0, omega_rate)
    sj = math.copysign(1.0, rate_j) == math.copysign(1.0, omega_rate)
    if si != sj:
        return 0 if si else 1
    return 0 if abs(omega_amp - amp_i) <= abs(omega_amp - amp_j) else 1

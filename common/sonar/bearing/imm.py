"""Interacting multiple model on the bearing rate for the bearing tracker (issue 13: a
contact passing close to the own ship, own-ship turns), on common.core.imm.

Choice (stated; 000 has one straight-line-segment model with one Q): two models with the
same F (000 F) and the Q of 000 with two bearing process-noise powers, a quiet one
(q_theta_quiet: straight contacts, a steady own ship; an accurate bearing rate, which
crossing management's memory mode coasts on) and a manoeuvre one (q_theta: own-ship
turns, the bearing acceleration near a closest approach). The amplitude and frequency
noise powers are the same in both. Mean sojourn times give the Markov chain for cycles
of any length (common.core.imm.transition). Association, gating, track quality and
crossing management use the combined (moment-matched) prediction; each model is updated
with the associated detection and the same 004 gain weight alpha; a track without a
detection (or with alpha = 0) keeps the predicted model probabilities.

Memory mode (004 claim 5; the description of Etp2's first mode, margin 25: "los parametros
para el calculo de prediccion de posicion ya no evolucionan"): a track in it predicts with
the quiet Q in both models (deviation: 004 has no Q at all; core.crossing deviation
iii). With the manoeuvre Q its covariance grew by q_theta over the whole crossing
although no detection could show a manoeuvre,
so the coasting tracks' gates spread over both targets and the first detections after
the ambiguity re-associated wrongly (GNN swaps on sonar_hold_cross_eq / _slow).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from common.core.angles import wrap_2pi, wrap_pi
from common.core.gating import quadratic_form
from common.core.imm import combine, gaussian_loglik, mix, probabilities, transition
from common.core.kalman import predict, update

QFunc = Callable[[np.ndarray, np.ndarray | float], np.ndarray]


class BearingImm:
    """Two-model IMM steps over the model arrays mu (N, 2), xm (N, 2, n), Pm (N, 2, n, n)."""

    def __init__(self, q_thetas: tuple[float, float], sojourn: tuple[float, float]) -> None:
        self.q = q_thetas
        self.sojourn = np.asarray(sojourn, dtype=float)
        self.mu0 = self.sojourn / self.sojourn.sum()  # stationary probabilities

    def predict(self, mu: np.ndarray, xm: np.ndarray, Pm: np.ndarray, T: np.ndarray,
                F: np.ndarray, Q: QFunc, memory: np.ndarray | None = None,
                q_manoeuvre: np.ndarray | None = None) -> tuple[np.ndarray, ...]:
        """Mixing and model-matched prediction (000 x^pre = F x, P^pre = F P F' + Q per
        model; the quiet Q in both models for the tracks flagged in `memory` (N,), 004
        memory mode; `q_manoeuvre` (N,): the manoeuvre model's power per track, default
        its q_theta): predicted probabilities c (N, 2), xm, Pm, combined x (N, n), P."""
        c, x0, P0 = mix(mu, _near(xm, xm[:, :1]), Pm, transition(T, self.sojourn))
        Q_quiet = Q(T, self.q[0])
        for j, q in enumerate(self.q):
            Qj = Q_quiet if j == 0 else Q(T, q if q_manoeuvre is None else q_manoeuvre)
            if j and memory is not None:
                Qj = np.where(memory[:, None, None], Q_quiet, Qj)
            x0[:, j], P0[:, j] = predict(x0[:, j], P0[:, j], F, Qj)
            x0[:, j, 0] = wrap_2pi(x0[:, j, 0])
        x, P = combine(c, _near(x0, x0[:, :1]), P0)
        x[:, 0] = wrap_2pi(x[:, 0])
        return c, x0, P0, x, P

    def update(self, c: np.ndarray, xm: np.ndarray, Pm: np.ndarray, rows: np.ndarray,
               z: np.ndarray, H: np.ndarray, R: np.ndarray, alpha: np.ndarray
               ) -> tuple[np.ndarray, ...]:
        """Update of the tracks `rows` with detections z (K, m), R (K, m, m), gain weights
        alpha (K,); returns mu, xm, Pm and the combined x, P of all N tracks."""
        mu = c.copy()
        if rows.size:
            ll = np.empty((rows.size, len(self.q)))
            for j in range(len(self.q)):
                y = z - xm[rows, j] @ H.T  # 000 y = z - H x^pre
                y[:, 0] = wrap_pi(y[:, 0])
                xu, Pu, S, _ = update(xm[rows, j], Pm[rows, j], y, H, R, joseph=True, gain_scale=alpha)
                xu[:, 0] = wrap_2pi(xu[:, 0])
                xm[rows, j], Pm[rows, j] = xu, Pu
                ll[:, j] = gaussian_loglik(quadratic_form(y, S), S)
            moved = alpha > 0
            mu[rows[moved]] = probabilities(c[rows[moved]], ll[moved])
        return (mu, xm, Pm, *self.combined(mu, xm, Pm))

    def combined(self, mu: np.ndarray, xm: np.ndarray, Pm: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The moment-matched x (N, n), P of the model states."""
        x, P = combine(mu, _near(xm, xm[:, :1]), Pm)
        x[:, 0] = wrap_2pi(x[:, 0])
        return x, P


def _near(xm: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """Model means with their bearings unwrapped next to ref's (no 0 / 2 pi split)."""
    out = xm.copy()
    out[..., 0] = ref[..., 0] + wrap_pi(xm[..., 0] - ref[..., 0])
    return out

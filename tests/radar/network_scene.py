"""Synthetic multistatic network for the tests of common.radar.network (and
benchmarks/network_fusion.py): receivers with 2-3 transmitters each, range-Doppler
only, unsynchronised, aircraft on straight legs.

Reports are elementary-track-like and come from a per-base Kalman filter (3-state
[r_b, v_b, gamma_b], the leading blocks of 001 [19], [20]) run on simulated (r_b, v_b)
plots of each aircraft, detected with probability pd at every scan of the base (a
missed scan is a prediction: updated = False). One elementary track per aircraft and
base, its number a per-base permutation; confirmed after 3 updates. Each base has its
own period and phase; a node's clock offset shifts the stamps of its reports (the
plots are taken at true time). Sites: local ENU metres, 0-600 m altitude.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from common.core import kalman
from common.core.gating import quadratic_form
from common.core.motion import bistatic_F, bistatic_Q
from common.core.track_table import Status
from common.radar.elementary.tracker import ElementaryTracks
from common.radar.geometry.bistatic import bistatic_range, bistatic_range_rate, project_jacobian

SIGMA_GAMMA = 5.0  # m/s^3, white jerk of the elementary filters (ElementaryParams default)
FM = (300.0, 1.0)  # sigma r_b (m), sigma v_b (m/s)
DVBT = (30.0, 0.5)


@dataclass(frozen=True)
class Base:
    """A bistatic base (BaseGeometry) with its accuracy and timing."""

    id: str
    tx: np.ndarray
    rx: np.ndarray
    sigma_r: float
    sigma_v: float
    period: float
    phase: float
    clock: float = 0.0


@dataclass(frozen=True)
class Scene:
    """Bases, aircraft (p0 (N, 3), v (N, 3) at t = 0) and the reports in arrival order."""

    bases: list[Base]
    p0: np.ndarray
    v: np.ndarray
    reports: list[tuple[int, float, ElementaryTracks]]

    def truth(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Positions and velocities (N, 3) at t."""
        return self.p0 + self.v * t, self.v


def network(rng: np.random.Generator, n_rx: int = 8, span: float = 150e3) -> list[Base]:
    """n_rx receivers over span x span, each with 2-3 of its nearest transmitters of a
    pool of n_rx + 2 (FM or DVB-T; 3 for the first half of the receivers, so >= 2.5
    n_rx bases), period 0.5-1 s and a random phase."""
    rx = np.column_stack([rng.uniform(-span / 2, span / 2, (n_rx, 2)), rng.uniform(0, 600, n_rx)])
    n_tx = n_rx + 2
    tx = np.column_stack([rng.uniform(-0.6 * span, 0.6 * span, (n_tx, 2)),
                          rng.uniform(100, 600, n_tx)])
    kind = rng.random(n_tx) < 0.5
    bases = []
    for i in range(n_rx):
        d = np.linalg.norm(tx[:, :2] - rx[i, :2], axis=1)
        d[d < 10e3] = np.inf  # no transmitter on the receiver's site
        for j in np.argsort(d)[:3 if i < n_rx // 2 else int(rng.integers(2, 4))]:
            sr, sv = DVBT if kind[j] else FM
            period = float(rng.uniform(0.5, 1.0))
            bases.append(Base(f"rx{i}tx{j}", tx[j], rx[i], sr, sv, period,
                              float(rng.uniform(0, period))))
    return bases


def aircraft(rng: np.random.Generator, n: int, span: float = 120e3) -> tuple[np.ndarray, np.ndarray]:
    """n aircraft over span x span at 1-12 km, 150-250 m/s level flight."""
    p0 = np.column_stack([rng.uniform(-span / 2, span / 2, (n, 2)), rng.uniform(1e3, 12e3, n)])
    head = rng.uniform(0, 2 * np.pi, n)
    speed = rng.uniform(150, 250, n)
    return p0, np.column_stack([speed * np.sin(head), speed * np.cos(head), np.zeros(n)])


def line(n: int, span: float = 100e3, z: float = 8e3) -> tuple[np.ndarray, np.ndarray]:
    """n aircraft evenly spaced on a straight line (ghost scene), one altitude, parallel."""
    x = np.linspace(-span / 2, span / 2, n)
    p0 = np.column_stack([x, 0.2 * x, np.full(n, z)])
    return p0, np.tile([0.0, 200.0, 0.0], (n, 1))


def formation(rng: np.random.Generator, n: int, size: float = 2e3, z: float = 8e3
              ) -> tuple[np.ndarray, np.ndarray]:
    """n aircraft within a size x size x size/4 box at z, one heading, 200 m/s +- 5 m/s
    (ghost scene: tight formation)."""
    p0 = rng.uniform(-size / 2, size / 2, (n, 3)) * [1, 1, 0.25] + [0.0, 0.0, z]
    v = np.column_stack([np.zeros(n), rng.uniform(195, 205, n), np.zeros(n)])
    return p0, v


def simulate(rng: np.random.Generator, bases: list[Base], p0: np.ndarray, v: np.ndarray,
             duration: float, pd: float = 0.9, latency: float = 0.3) -> Scene:
    """Every base's reports over [0, duration), delivered in order of true time plus a
    uniform latency in [0, latency] s."""
    out: list[tuple[float, int, float, ElementaryTracks]] = []
    n = p0.shape[0]
    for b, base in enumerate(bases):
        perm = rng.permutation(n) + 1
        x = np.zeros((n, 3))
        P = np.zeros((n, 3, 3))
        hits = np.zeros(n, dtype=int)
        t_prev = 0.0
        R = np.diag([base.sigma_r ** 2, base.sigma_v ** 2])
        for t in np.arange(base.phase, duration, base.period):
            pos = p0 + v * t
            y = np.column_stack([bistatic_range(pos, base.tx, base.rx),
                                 bistatic_range_rate(pos, v, base.tx, base.rx)])
            z = y + rng.standard_normal((n, 2)) * [base.sigma_r, base.sigma_v]
            det = rng.random(n) < pd
            dt = t - t_prev
            xp, Pp = kalman.predict(x, P, bistatic_F(dt)[:3, :3],
                                    bistatic_Q(dt, SIGMA_GAMMA, 0.0)[:3, :3])
            new = det & (hits == 0)
            xp[new] = np.column_stack([z[new], np.zeros(new.sum())])
            Pp[new] = np.diag([base.sigma_r ** 2, base.sigma_v ** 2, 400.0])
            upd = det & (hits > 0)
            xu, Pu, _, _ = kalman.update(xp[upd], Pp[upd], z[upd] - xp[upd, :2], np.eye(3)[:2], R)
            xp[upd], Pp[upd] = xu, Pu
            x, P, t_prev = xp, Pp, t
            hits += det
            live = np.flatnonzero(hits > 0)
            order = live[np.argsort(perm[live])]
            status = np.where(hits[order] >= 3, Status.CONFIRMED, Status.TENTATIVE)
            rep = ElementaryTracks(
                float(t + base.clock), perm[order], status.astype(np.int64), x[order].copy(),
                P[order].copy(), np.zeros(order.size), np.ones(order.size, dtype=np.int64),
                det[order].copy(), np.zeros(order.size, dtype=bool))
            out.append((t + rng.uniform(0, latency), b, rep.t, rep))
    out.sort(key=lambda e: e[0])
    return Scene(bases, p0, v, [(b, t, r) for _, b, t, r in out])


def crlb_position(bases: list[Base], pos: np.ndarray, vel: np.ndarray) -> np.ndarray:
    """sqrt(trace) of the position block of the inverse Fisher information of one
    (r_b, v_b) report of every base (001 [47]'s Jacobian), per aircraft (N,)."""
    x = np.zeros((pos.shape[0], 6))
    x[:, [0, 2, 4]], x[:, [1, 3, 5]] = pos, vel
    info = np.zeros((pos.shape[0], 6, 6))
    for b in bases:
        J = project_jacobian(x, b.tx, b.rx)[:, :2]
        Ri = np.diag([b.sigma_r ** -2, b.sigma_v ** -2])
        info += np.swapaxes(J, 1, 2) @ Ri @ J
    C = np.linalg.inv(info)
    return np.sqrt(C[:, 0, 0] + C[:, 2, 2] + C[:, 4, 4])


@dataclass
class Score:
    """Counts over the reports after ``warm_up``: missed aircraft, duplicates, false tracks
    (confirmed, farther than ``near`` from every aircraft), number switches; per aircraft
    the mean squared position error, mean squared CRLB and the number of samples."""

    missed: int
    duplicates: int
    false: int
    switches: int
    scans: int
    err2: np.ndarray
    crlb2: np.ndarray
    cnt: np.ndarray
    nees: float

    def rmse_over_crlb(self) -> float:
        """Position RMSE over the rms CRLB, pooled over every aircraft and sample."""
        return float(np.sqrt(np.sum(self.err2 * self.cnt) / max(np.sum(self.crlb2 * self.cnt), 1e-300)))


def score(scene: Scene, reports: list, warm_up: float = 15.0, near: float = 2000.0) -> Score:
    """Each confirmed track of a report (NetworkReport) against its nearest aircraft."""
    n = scene.p0.shape[0]
    missed = dup = false = switches = scans = 0
    err2, crlb2, cnt = np.zeros(n), np.zeros(n), np.zeros(n)
    holder = np.full(n, -1)
    nees: list[np.ndarray] = []
    for rep in reports:
        if rep.t < warm_up:
            continue
        scans += 1
        pos, vel = scene.truth(rep.t)
        conf = rep.status != Status.TENTATIVE
        X = rep.x[conf][:, [0, 2, 4]]
        d = np.linalg.norm(X[:, None] - pos[None], axis=2) if X.size else np.full((0, n), np.inf)
        a = d.argmin(axis=1) if X.size else np.zeros(0, dtype=int)
        dist = d[np.arange(a.size), a]
        ok = dist <= near
        false += int((~ok).sum())
        held = np.bincount(a[ok], minlength=n)
        missed += int((held == 0).sum())
        dup += int((held > 1).sum())
        ids = np.full(n, -1)
        for i in np.flatnonzero(ok)[np.argsort(-dist[ok])]:  # the nearest track last
            ids[a[i]] = rep.id[conf][i]
        switches += int(((holder >= 0) & (ids >= 0) & (ids != holder)).sum())
        holder = np.where(ids >= 0, ids, holder)
        e = X[ok] - pos[a[ok]]
        np.add.at(err2, a[ok], np.sum(e ** 2, axis=1))
        np.add.at(crlb2, a[ok], crlb_position(scene.bases, pos[a[ok]], vel[a[ok]]) ** 2)
        np.add.at(cnt, a[ok], 1)
        C = rep.P[conf][ok][:, [0, 2, 4]][:, :, [0, 2, 4]]
        nees.append(quadratic_form(e, C))
    c = np.maximum(cnt, 1)
    return Score(missed, dup, false, switches, scans, err2 / c, crlb2 / c, cnt,
                 float(np.concatenate(nees).mean()) if nees else float("nan"))

"""Scoring of a network's global tracks against the simulator's truth, shared by the
in-process chain test (tests/wire/test_network_chain.py) and the multi-process one
(tests/integration/test_network_integration.py)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from common.core.gating import quadratic_form
from common.wire.sim_messages import truth_state

XYZ = [0, 2, 4]
HELD = 3000.0  # m: a confirmed track within this of an aircraft holds it


@dataclass
class NetworkScore:
    """After the warm-up, over every gtracks message: reports scored, aircraft-reports
    not held by a confirmed track, confirmed tracks held by no aircraft (false),
    confirmed tracks whose nearest aircraft is another track's nearest too
    (duplicates), and the position NEES of each aircraft's nearest confirmed track."""

    reports: int = 0
    missed: int = 0
    false: int = 0
    duplicates: int = 0
    nees: list[float] = field(default_factory=list)


def score(gtracks: list[dict[str, Any]], truth: dict[float, dict[str, Any]], warmup: float
          ) -> NetworkScore:
    """Score gtracks messages (decoded) against sim/truth/radar messages keyed by t."""
    s = NetworkScore()
    for g in gtracks:
        if g["t"] < warmup:
            continue
        X = truth_state(truth[g["t"]])[:, XYZ]
        conf = [k for k in g["tracks"] if k["status"] == "confirmed"]
        x = np.array([k["x"] for k in conf]).reshape(-1, 6)[:, XYZ]
        P = np.array([k["P"] for k in conf]).reshape(-1, 6, 6)[:, XYZ][:, :, XYZ]
        d = np.linalg.norm(X[:, None] - x[None], axis=2).reshape(len(X), len(x))
        s.reports += 1
        held = d <= HELD
        s.missed += int((~held.any(axis=1)).sum())
        s.false += int((~held.any(axis=0)).sum())
        near = d[:, held.any(axis=0)].argmin(axis=0) if len(x) else np.zeros(0, dtype=int)
        s.duplicates += near.size - np.unique(near).size
        rows = np.flatnonzero(held.any(axis=1))
        j = d[rows].argmin(axis=1)
        s.nees += quadratic_form(X[rows] - x[j], P[j]).tolist()
    return s

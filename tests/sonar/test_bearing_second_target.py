"""A second target's young track next to a confirmed track (issue 13, sonar_cross_4dpm_eq
seed 33 lost its second target this way): it keeps the detections the confirmed track
did not take (common.sonar.bearing.assoc) and is not merged into the confirmed track
while its bearing rate differs (common.sonar.bearing.merge, 000 d_merge over the state)."""

from __future__ import annotations

import math

import numpy as np

from common.sonar.bearing.assoc import associate
from common.sonar.bearing.merge import merged_tentative
from common.sonar.bearing.model import measurement_matrix

SIG = math.radians(1.0)
RATE = math.radians(2.0) / 60.0  # 2 deg/min, rad/s
P = np.diag([(0.5 * SIG) ** 2, (0.1 * RATE) ** 2, 1.0, 1e-4])  # settled: rate to 10 %


def test_opposite_bearing_rates_are_not_one_target() -> None:
    x = np.array([[1.0, -RATE, 12.0, 0.0],          # confirmed, falling
                  [1.0 + SIG, RATE, 12.0, 0.0],     # tentative, rising, 1 deg away
                  [1.0 + SIG, -RATE, 12.0, 0.0]])   # tentative, falling with it: a duplicate
    conf = np.array([True, False, False])
    out = merged_tentative(x, np.repeat(P[None], 3, axis=0), conf, 9.21)
    assert out.tolist() == [False, False, True]


def test_tentative_track_takes_a_gated_detection_the_confirmed_one_left() -> None:
    H = measurement_matrix(False)
    x = np.array([[1.0, 0.0, 12.0, 0.0], [1.0 + 3 * SIG, 0.0, 12.0, 0.0]])  # confirmed, tentative
    Ps = np.repeat(P[None], 2, axis=0)
    conf = np.array([True, False])
    args = (Ps, H)
    kw = dict(confirmed=conf, p_d=np.full(2, 0.9), p_d_max=0.9, beam=math.radians(2.0))

    def pairs(brg: list[float]) -> tuple[dict[int, int], np.ndarray]:
        z = np.column_stack([brg, np.full(len(brg), 12.0)])
        Rd = np.tile([SIG**2, 4.0], (len(brg), 1))
        rows, cols, _, _, _, gated = associate(x, *args, z, Rd, p_fa=np.full(len(brg), 1e-3), **kw)
        return dict(zip(rows.tolist(), cols.tolist())), gated

    both, gated = pairs([1.0 + 0.1 * SIG, 1.0 + 2.9 * SIG])  # each target's detection
    assert gated.tolist() == [True, True]  # both inside the confirmed gate
    assert both == {0: 0, 1: 1}
    one, gated = pairs([1.0 + 1.4 * SIG])  # one detection between them: the confirmed track's
    assert one == {0: 0} and gated.tolist() == [True]

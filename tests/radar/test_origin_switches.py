"""benchmarks/origin_switches.py (issue 14 diagnostic): switches by origin of the
elementary tracks versus the GOSPA switches of the scoring."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from common.radar.elementary.tracker import ElementaryTracks
from common.radar.fusion.report import GlobalTracks
from common.radar.geometry.bistatic import project

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from origin_switches import OriginLabels  # noqa: E402

TX = np.array([[-35000.0, 20000.0, 300.0], [45000.0, 10000.0, 500.0]])
RX = np.array([[0.0, 0.0, 30.0], [0.0, 0.0, 30.0]])
TRUTH_IDS = np.array([7, 8])
TRUTH_X = np.array([[30000.0, 100.0, 20000.0, 0.0, 5000.0, 0.0],
                    [-20000.0, 0.0, 30000.0, 150.0, 3000.0, 0.0]])


def etracks(b: int) -> ElementaryTracks:
    """Elementary tracks 1 (on truth 7) and 2 (on truth 8) of base b, exact."""
    x = np.zeros((2, 5))
    x[:, [0, 1, 3]] = project(TRUTH_X, TX[b], RX[b])
    P = np.tile(np.diag([150.0**2, 2.0**2, 1.0, 1e-4, 1e-6]), (2, 1, 1))
    n = np.ones(2, dtype=bool)
    return ElementaryTracks(0.0, np.array([1, 2]), np.ones(2, dtype=np.int64), x, P,
                            np.ones(2), np.ones(2, dtype=np.int64), n, ~n)


def gtracks(members: list[int]) -> GlobalTracks:
    """Global tracks 10 and 20 holding, at both bases, elementary tracks `members`."""
    m = np.array([[members[0]] * 2, [members[1]] * 2])
    return GlobalTracks(0.0, ("b1", "b2"), np.array([10, 20]), np.ones(2, dtype=np.int64),
                        np.zeros((2, 6)), np.tile(np.eye(6), (2, 1, 1)), np.ones(2), m,
                        np.ones((2, 2), dtype=bool), np.zeros(2, dtype=bool))


def run(members: list[list[int]], gospa: list[dict[int, int | None]]) -> tuple[int, int, int]:
    o = OriginLabels(TX, RX)
    for mem, g in zip(members, gospa):
        for b in range(2):
            o.etracks(b, etracks(b), TRUTH_IDS, TRUTH_X)
        o.cycle(gtracks(mem), np.ones(2, dtype=bool), TRUTH_IDS, g)
    return o.summary(gospa)


def test_fed_by_the_other_truth_is_an_origin_switch() -> None:
    held = {7: 10, 8: 20}
    swapped = {7: 20, 8: 10}
    assert run([[1, 2], [2, 1]], [held, swapped]) == (2, 2, 0)


def test_scoring_crossing_of_correctly_fed_tracks() -> None:
    held = {7: 10, 8: 20}
    crossed = {7: 20, 8: 10}
    assert run([[1, 2], [1, 2], [1, 2]], [held, crossed, held]) == (0, 4, 4)

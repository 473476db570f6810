"""The factory of global fusion's core (common.radar.fusion_core): 001's GlobalFusion
for azimuth bases on one receiver, NetworkFusion for several receivers or range-Doppler
bases, a ValueError for bases neither can fuse; the network core behind the role."""

from __future__ import annotations

import numpy as np
import pytest

from common.core.rejection import Rejected
from common.core.track_table import Status
from common.deploy.config import RadarBase
from common.radar.elementary.tracker import ElementaryParams, ElementaryTracks
from common.radar.fusion.params import FusionParams
from common.radar.fusion_core import Network, SingleReceiver, fusion_core

RX = np.array([0.0, 0.0, 100.0])
TX = [np.array([30e3, 0.0, 300.0]), np.array([0.0, 40e3, 300.0]), np.array([-35e3, -5e3, 200.0])]
RX2 = np.array([60e3, 50e3, 200.0])


def core(bases: list[RadarBase], tracker: ElementaryParams = ElementaryParams()):
    return fusion_core(bases, FusionParams(), None, tracker)


def bases(azimuth: bool = True, receivers: tuple[np.ndarray, ...] = (RX,)) -> list[RadarBase]:
    return [RadarBase(f"b{k}{j}", tx, rx, ["c1"], 1, azimuth)
            for j, rx in enumerate(receivers) for k, tx in enumerate(TX)]


def report(t: float, n_state: int) -> ElementaryTracks:
    x = np.zeros((1, n_state))
    x[0, 0] = 80e3
    return ElementaryTracks(t, np.array([1]), np.array([Status.CONFIRMED]), x,
                            np.eye(n_state)[None] * 100.0, np.zeros(1), np.ones(1, np.int64),
                            np.ones(1, bool), np.zeros(1, bool))


def test_azimuth_bases_on_one_receiver_keep_001() -> None:
    c = core(bases())
    assert isinstance(c, SingleReceiver) and c.bases == ("b00", "b10", "b20")
    assert c.flush() == []


@pytest.mark.parametrize("azimuth, receivers", [(True, (RX, RX2)), (False, (RX, RX2))])
def test_several_receivers_or_range_doppler_take_the_network_core(
        azimuth: bool, receivers: tuple[np.ndarray, ...]) -> None:
    tracker = ElementaryParams(sigma_gamma=3.0, sigma_omega=2e-3)
    c = core(bases(azimuth, receivers), tracker)
    assert isinstance(c, Network) and len(c.bases) == 6
    assert (c.core.dec.sigma_gamma, c.core.dec.sigma_omega) == (3.0, 2e-3)  # [radar.tracker]'s Q [20]


def test_mixed_bases_take_the_network_core() -> None:
    b = bases()
    b[0] = RadarBase(b[0].id, b[0].tx, RX2, ["c1"], 1, False)
    assert isinstance(core(b), Network)


@pytest.mark.parametrize("b, match", [
    (bases(False), "b00, b10, b20 declared azimuth = false"),  # one receiver, range-Doppler
    (bases(False, (RX, RX2))[2:4], "2 bases over 2 receiver"),
    (bases()[:1], "sharing one receiver"),  # 001 refuses a single base
])
def test_bases_neither_core_fuses_are_refused(b: list[RadarBase], match: str) -> None:
    with pytest.raises(ValueError, match=match):
        core(b)


def test_network_core_reports_as_global_tracks_and_counts_too_late() -> None:
    c = core(bases(False, (RX, RX2)))
    assert isinstance(c, Network)
    assert c.push("b00", report(0.0, 3), now=123.0) == []  # in the reordering window
    out = c.push("b11", report(3.0, 3), now=-5.0)  # wall time is not used
    assert [g.t for g in out] == [0.0] and out[0].bases == c.bases
    with pytest.raises(Rejected) as e:
        c.push("b01", report(0.0, 3), now=0.0)
    assert e.value.reason == "too_late" and c.core.rejected == {"too_late": 1}
    assert [g.t for g in c.flush()] == [3.0]

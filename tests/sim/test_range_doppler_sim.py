"""The simulator at a range-Doppler base (azimuth = false): no az, saz columns, the
same draws (its r_b, v_b columns equal those of the base declared with azimuth)."""

from __future__ import annotations

import dataclasses

from tests.sim.test_simulator import BASES, radar_doc, run


def test_no_azimuth_columns_same_draws() -> None:
    rd = [dataclasses.replace(b, azimuth=False) for b in BASES]
    for (t1, m1), (t2, m2) in zip(run(radar_doc(), seed=4), run(radar_doc(), bases=rd, seed=4), strict=True):
        assert t1 == t2
        for (k1, a), (k2, b) in zip(m1, m2, strict=True):
            assert k1 == k2
            if k1.startswith("radar/plots/"):
                assert "az" in a and "az" not in b and "saz" not in b
                assert {k: v for k, v in a.items() if k not in ("az", "saz")} == b

"""Sites on the Earth (issue 29): [radar.origin] and tx_geo / rx_geo of [[radar.base]],
converted to the local ENU metres every core uses."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from common.deploy.config import ConfigError, parse
from common.deploy.sections import check_tables
from common.radar.geometry.geodesy import LocalFrame

ORIGIN = {"lat": 48.5, "lon": 2.0, "alt": 80.0}


def doc(base: dict[str, Any], origin: dict[str, Any] | None = ORIGIN) -> dict[str, Any]:
    radar: dict[str, Any] = {"base": [{"id": "b1", "channels": ["c1"], **base}]}
    if origin is not None:
        radar["origin"] = origin
    return {"radar": radar}


def test_geodetic_sites_become_local_metres() -> None:
    cfg = parse(doc({"tx_geo": [49.4, 2.0, 300.0], "rx": [1000.0, -2000.0, 10.0]}))
    assert cfg.origin == LocalFrame(48.5, 2.0, 80.0)
    b = cfg.base("b1")
    np.testing.assert_array_equal(b.rx, [1000.0, -2000.0, 10.0])
    assert abs(b.tx[0]) < 1e-6 and 99e3 < b.tx[1] < 101e3  # 0.9 deg North, ~100 km
    assert b.tx[2] < 300.0 - 80.0 - 700.0  # below the tangent plane: ~ -d^2 / (2 R)
    np.testing.assert_allclose(cfg.origin.to_geodetic(b.tx), [49.4, 2.0, 300.0], atol=1e-9)
    check_tables(cfg)  # [radar.origin] is a known table


def test_flat_deployment_has_no_origin() -> None:
    cfg = parse(doc({"tx": [30e3, 0.0, 100.0], "rx": [0.0, 0.0, 10.0]}, origin=None))
    assert cfg.origin is None
    np.testing.assert_array_equal(cfg.base("b1").tx, [30e3, 0.0, 100.0])


@pytest.mark.parametrize("base,origin,key,match", [
    ({"tx": [1.0, 0, 0], "tx_geo": [48.6, 2.0, 0.0], "rx": [0, 0, 0]}, ORIGIN,
     "radar.base[0].tx", "exactly one of tx"),
    ({"rx": [0, 0, 0]}, ORIGIN, "radar.base[0].tx", "exactly one of tx"),
    ({"tx": [1.0, 0, 0]}, ORIGIN, "radar.base[0].rx", "exactly one of rx"),
    ({"tx": [1.0, 0, 0], "rx_geo": [48.6, 2.0, 0.0]}, None, "radar.base[0].rx_geo", r"needs \[radar.origin\]"),
    ({"tx_geo": [91.0, 2.0, 0.0], "rx": [0, 0, 0]}, ORIGIN, "radar.base[0].tx_geo", "lat"),
    ({"tx_geo": [48.0, 181.0, 0.0], "rx": [0, 0, 0]}, ORIGIN, "radar.base[0].tx_geo", "lon"),
    ({"tx_geo": [48.0, 2.0], "rx": [0, 0, 0]}, ORIGIN, "radar.base[0].tx_geo", "lat_deg"),
    ({"tx": [1.0, 0, 0], "rx": [0, 0, 0]}, {"lat": 48.0, "lon": 2.0}, "radar.origin", "alt"),
    ({"tx": [1.0, 0, 0], "rx": [0, 0, 0]}, {"lat": 95.0, "lon": 2.0, "alt": 0.0}, "radar.origin", "lat"),
    ({"tx": [1.0, 0, 0], "rx": [0, 0, 0]}, {**ORIGIN, "h": 1.0}, "radar.origin", "exactly"),
])
def test_errors_name_the_key(base: dict[str, Any], origin: dict[str, Any] | None, key: str, match: str) -> None:
    with pytest.raises(ConfigError, match=match) as e:
        parse(doc(base, origin))
    assert e.value.key == key

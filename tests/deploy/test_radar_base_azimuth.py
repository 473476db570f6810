"""[[radar.base]] azimuth: true by default, false for a range-Doppler base, a bool."""

from __future__ import annotations

import pytest

from common.deploy.config import ConfigError, parse


def doc(**extra: object) -> dict:
    base = {"id": "b1", "tx": [1e4, 0.0, 0.0], "rx": [0.0, 0.0, 0.0], "channels": ["c1"], **extra}
    return {"radar": {"base": [base]}}


def test_azimuth_default_true_and_false() -> None:
    assert parse(doc()).bases[0].azimuth is True
    assert parse(doc(azimuth=False)).bases[0].azimuth is False


def test_azimuth_must_be_a_bool() -> None:
    with pytest.raises(ConfigError) as e:
        parse(doc(azimuth="no"))
    assert "radar.base[0].azimuth" in str(e.value)

"""The ``[sim.radar]`` tables of a scenario file: per-channel sensor models, the
surveillance window, SNR and detection model, per-base timing and the targets
(docs/scenarios.md lists every key)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from common.core.params import Params, Range, positive, unbounded
from common.deploy.config import ConfigError
from common.sim.mover import Mover
from common.sim.parse import AIR_KEYS, CLUTTER, DB, PD, checked, listed, mover, num, table, unique_ids

PD_MODELS = ("fixed", "snr")  # Bernoulli(pd); or SNR above the threshold and Bernoulli(pd)


@dataclass(frozen=True)
class RadarChannelSim(Params):
    """Per-channel radar sensor model: pd, clutter mean, sigmas, reference SNR."""

    pd: float = 0.9
    clutter: float = 1.0
    srb: float = 150.0
    svb: float = 2.0
    saz: float = math.radians(1.5)
    snr_db: float = 15.0

    RANGES: ClassVar[dict[str, Range]] = {
        "pd": PD, "clutter": CLUTTER, "srb": positive("m"), "svb": positive("m/s"),
        "saz": Range("rad", 0.0, math.pi, "(]"), "snr_db": unbounded("dB", DB),
    }


@dataclass(frozen=True)
class RadarSim:
    """Radar part of a scenario; pd_model one of PD_MODELS (common.sim.radar)."""

    default: RadarChannelSim
    channels: dict[str, RadarChannelSim]
    targets: list[Mover]
    scan_period: float
    rb_max: float = 200e3
    vb_max: float = 600.0
    snr_threshold_db: float = 10.0
    snr_sigma_db: float = 1.0
    snr_ref_range: float = 50e3
    clutter_snr_db: float = 2.0
    pd_model: str = "fixed"
    timing: dict[str, tuple[float, float]] = field(default_factory=dict)  # base: period, phase

    def channel(self, cid: str) -> RadarChannelSim:
        return self.channels.get(cid, self.default)

    def base_times(self, base: str, duration: float) -> np.ndarray:
        """Scan times of a base: phase + k period in [0, duration) ([sim.radar.base.<id>]),
        else the common k scan_period."""
        period, phase = self.timing.get(base, (self.scan_period, 0.0))
        return phase + np.arange(int(np.ceil((duration - phase) / period - 1e-9))) * period


_RCH_KEYS = {"pd", "clutter", "srb", "svb", "saz_deg", "snr_db"}


def _radar_channel(t: dict[str, Any], key: str, base: RadarChannelSim) -> RadarChannelSim:
    return checked(
        RadarChannelSim, key,
        pd=num(t, "pd", key, base.pd),
        clutter=num(t, "clutter", key, base.clutter),
        srb=num(t, "srb", key, base.srb),
        svb=num(t, "svb", key, base.svb),
        saz=math.radians(num(t, "saz_deg", key, math.degrees(base.saz))),
        snr_db=num(t, "snr_db", key, base.snr_db),
    )


def radar_section(t: Any, period: float) -> RadarSim:
    key = "sim.radar"
    win = {"rb_max", "vb_max", "snr_threshold_db", "snr_sigma_db", "snr_ref_range",
           "clutter_snr_db", "pd_model", "channel", "target", "base"}
    t = table(t, key, _RCH_KEYS | win)
    default = _radar_channel(t, key, RadarChannelSim())
    chans_raw = table(t.get("channel", {}), f"{key}.channel", set(t.get("channel", {})))
    chans = {
        c: _radar_channel(table(v, f"{key}.channel.{c}", _RCH_KEYS), f"{key}.channel.{c}", default)
        for c, v in chans_raw.items()
    }
    targets = [
        mover(m, f"{key}.target[{i}]", AIR_KEYS, (3,))[0]
        for i, m in enumerate(listed(t, "target", key))
    ]
    unique_ids(targets, f"{key}.target")
    pd_model = t.get("pd_model", "fixed")
    if pd_model not in PD_MODELS:
        raise ConfigError(f"{key}.pd_model", f"must be one of {PD_MODELS}")
    timing = {}
    for b, v in table(t.get("base", {}), f"{key}.base", set(t.get("base", {}))).items():
        k = f"{key}.base.{b}"
        v = table(v, k, {"period", "phase"})
        bp = num(v, "period", k, period, 0.0, lo_open=True)
        timing[b] = (bp, num(v, "phase", k, 0.0, 0.0, bp))
        if timing[b][1] == bp:
            raise ConfigError(f"{k}.phase", f"must be below the period {bp}")
    return RadarSim(
        default, chans, targets, period, timing=timing, pd_model=pd_model,
        rb_max=num(t, "rb_max", key, 200e3, 0.0, lo_open=True),
        vb_max=num(t, "vb_max", key, 600.0, 0.0, lo_open=True),
        snr_threshold_db=num(t, "snr_threshold_db", key, 10.0),
        snr_sigma_db=num(t, "snr_sigma_db", key, 1.0, 0.0),
        snr_ref_range=num(t, "snr_ref_range", key, 50e3, 0.0, lo_open=True),
        clutter_snr_db=num(t, "clutter_snr_db", key, 2.0, 0.0, lo_open=True),
    )

"""Plots of external feeds (a blah2 node, a CSV file) as `radar/plots/<base>/<channel>`
messages (docs/protocol.md), with the time rules of the channel plotter
(common.radar.plots.stamps) per stream. Pure: wall time is passed in.

CSV columns (header row, comma-separated; docs/networks.md): `t` (UNIX s), `base`,
`channel`, `delay_km` or `rb_m`, `doppler_hz` or `vb_mps`, and optionally `az_deg`,
`snr_db`, `srb_m`, `svb_mps`, `saz_deg` (empty cells: absent). Consecutive rows of one
(t, base, channel) form one message.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

from common.core.angles import wrap_2pi
from common.core.rejection import Rejected
from common.deploy.config import RadarBase
from common.radar.plots.stamps import StampCheck
from common.radar.plots.units import IngestParams, delay_to_rb, doppler_to_vb, sigmas
from common.wire import protocol
from common.wire.blah2 import Frame

Message = tuple[str, dict[str, Any]]


def plots_message(base: str, channel: str, t: float, seq: int, cols: dict[str, np.ndarray]) -> Message:
    """(key suffix, plots message) of one channel's plots at t (columns rb, vb, srb, svb
    and optional az, saz, snr)."""
    return f"radar/plots/{base}/{channel}", {
        "v": protocol.VERSION, "t": t, "seq": seq, "base": base, "channel": channel,
        **{k: np.asarray(v, dtype=float).tolist() for k, v in cols.items()}}


@dataclass
class Units:
    """How a base's delays and Doppler shifts become r_b, v_b: the baseline L (m), fc,
    fs (Hz; 0: unknown) and the base's IngestParams."""

    baseline: float
    fc: float
    fs: float
    params: IngestParams

    def plots(self, delay_km: np.ndarray, doppler_hz: np.ndarray, snr_db: np.ndarray | None
              ) -> dict[str, np.ndarray]:
        """Columns rb, vb, srb, svb (and snr) of detections (module common.radar.plots.units)."""
        if self.fc <= 0 or (self.fs <= 0 and self.params.srb <= 0):
            raise Rejected("units", "fc (and fs, without a fixed srb) unknown: set [radar.ingest] fc, fs")
        srb, svb = sigmas(snr_db, len(delay_km), self.fc, self.fs or 1.0, self.params)
        cols = {"rb": delay_to_rb(delay_km, self.baseline), "vb": doppler_to_vb(doppler_hz, self.fc),
                "srb": srb, "svb": svb}
        return cols if snr_db is None else {**cols, "snr": np.asarray(snr_db, dtype=float)}


class NodeFeed:
    """The frames of one blah2 node -> plots messages of its base's single channel:
    each new frame once, t = stamp + time_offset, the time rules of StampCheck."""

    def __init__(self, base: RadarBase, units: Units, max_ahead: float) -> None:
        if len(base.channels) != 1:
            raise ValueError(f"base {base.id} has {len(base.channels)} channels; a node feeds one")
        self.base, self.units = base, units
        self.stamps = StampCheck(base.id, max_ahead)
        self.seq = 0

    def message(self, frame: Frame, now: float | None = None) -> Message:
        """The plots message of a frame (raises Rejected: `duplicate`, `time_backwards`,
        `ahead`, `units`)."""
        t = frame.t + self.units.params.time_offset
        cols = self.units.plots(frame.delay, frame.doppler, frame.snr)
        self.stamps.accept(t, now)
        self.seq += 1
        return plots_message(self.base.id, self.base.channels[0], t, self.seq - 1, cols)

    def newer(self, frames: list[Frame]) -> list[Frame]:
        """The frames after the last one taken (a stash after an outage)."""
        last = self.stamps.last
        off = self.units.params.time_offset
        return [f for f in frames if last is None or f.t + off > last]


RB_COLS = ("delay_km", "rb_m")
VB_COLS = ("doppler_hz", "vb_mps")


def csv_rows(text: str) -> Iterator[dict[str, str] | Rejected]:
    """The rows of a CSV text as dicts, or a Rejected `csv` for a malformed file."""
    reader = csv.DictReader(io.StringIO(text))
    names = set(reader.fieldnames or ())
    missing = [c for c in ("t", "base", "channel") if c not in names]
    if missing or not names & set(RB_COLS) or not names & set(VB_COLS):
        yield Rejected("csv", f"header {sorted(names)} lacks t, base, channel, delay_km or rb_m, "
                              "doppler_hz or vb_mps")
        return
    yield from reader


def _num(row: dict[str, str], k: str) -> float | None:
    v = (row.get(k) or "").strip()
    if not v:
        return None
    try:
        x = float(v)
    except ValueError:
        raise Rejected("csv", f"{k} = {v!r} is not a number") from None
    if not math.isfinite(x):
        raise Rejected("nan", f"{k} = {v!r}")
    return x


class CsvFeed:
    """CSV rows -> plots messages, with each (base, channel)'s time rules; `units` per
    base for delay_km / doppler_hz rows."""

    def __init__(self, bases: list[RadarBase], units: dict[str, Units], max_ahead: float) -> None:
        self.bases = {b.id: b for b in bases}
        self.units, self.max_ahead = units, max_ahead
        self.stamps: dict[tuple[str, str], StampCheck] = {}
        self.seq: dict[tuple[str, str], int] = {}

    def row(self, row: dict[str, str]) -> tuple[tuple[float, str, str], dict[str, float]]:
        """((t, base, channel), the row's numeric columns in plot units) (raises Rejected)."""
        base, channel = (row.get("base") or "").strip(), (row.get("channel") or "").strip()
        if base not in self.bases:
            raise Rejected("unknown_base", f"base {base!r} is not in the deployment")
        if channel not in self.bases[base].channels:
            raise Rejected("unknown_channel", f"channel {channel!r} is not a channel of {base}")
        t = _num(row, "t")
        if t is None:
            raise Rejected("csv", "t is empty")
        v = {k: _num(row, k) for k in ("delay_km", "rb_m", "doppler_hz", "vb_mps", "az_deg", "snr_db",
                                       "srb_m", "svb_mps", "saz_deg")}
        if v["delay_km"] is not None and v["delay_km"] < 0 or v["rb_m"] is not None and v["rb_m"] < 0:
            raise Rejected("negative_delay", "delay_km or rb_m < 0")
        if v["delay_km"] is None and v["rb_m"] is None or v["doppler_hz"] is None and v["vb_mps"] is None:
            raise Rejected("csv", "a row needs delay_km or rb_m, and doppler_hz or vb_mps")
        if (v["az_deg"] is None) != (v["saz_deg"] is None):
            raise Rejected("csv", "az_deg and saz_deg come together")
        out = {k: x for k, c in (("rb", "rb_m"), ("vb", "vb_mps"), ("srb", "srb_m"), ("svb", "svb_mps"),
                                 ("snr", "snr_db")) if (x := v[c]) is not None}
        if len(out) - ("snr" in out) < 4:  # something to convert: the base's units
            u = self.units[base]
            snr = None if v["snr_db"] is None else np.array([v["snr_db"]])
            conv = u.plots(np.array([v["delay_km"] or 0.0]), np.array([v["doppler_hz"] or 0.0]), snr)
            out = {k: float(a[0]) for k, a in conv.items()} | out
        if v["az_deg"] is not None and v["saz_deg"] is not None:
            out["az"] = float(wrap_2pi(np.radians(v["az_deg"])))
            out["saz"] = math.radians(v["saz_deg"])
        return (t, base, channel), out

    def message(self, key: tuple[float, str, str], rows: list[dict[str, float]], now: float | None = None
                ) -> Message:
        """The plots message of one (t, base, channel) group (raises Rejected)."""
        t, base, channel = key
        kinds = {frozenset(r) for r in rows}
        if len(kinds) > 1:
            raise Rejected("lengths", f"{base}/{channel} t={t}: rows with different columns")
        check = self.stamps.setdefault((base, channel), StampCheck(f"{base}/{channel}", self.max_ahead))
        check.accept(t, now)
        seq = self.seq[(base, channel)] = self.seq.get((base, channel), -1) + 1
        cols = {k: np.array([r[k] for r in rows]) for k in rows[0]}
        return plots_message(base, channel, t, seq, cols)

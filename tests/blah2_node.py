"""Fake blah2 nodes for tests: one aiohttp server on a free loopback port serving, under
/<base>/, the API of a blah2 node (``/api/detection``: the latest frame only,
``/stash/detection``: the frames of the last 300 s, one row per detection, no SNR,
``/api/config``) made of the simulator's plots of that base, released as wall time
passes (``speed`` times real time, from ``start``). A node stamps its frames ``lead``
s before the scan (blah2 stamps the start of processing) in integer milliseconds, and
drops plots with r_b below the baseline (its delay window starts at 0). Faults
(``Fault``) are queued per node and each served once in place of a frame."""

from __future__ import annotations

import asyncio
import json
import threading
import time
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from aiohttp import web

from common.bus.transport import free_port
from common.deploy.config import Config, load
from common.radar.plots.units import C
from common.sim.scenario import load_scenario
from common.sim.simulator import RadarScan, RadarTruth, scans

EPOCH_MS = 1_700_000_000_000
STASH_S = 300.0


@dataclass
class Fault:
    """Served once at the first request after scenario time `at`: `json`, `lengths`,
    `nan`, `negative` (a delay < 0), `back` (a stamp 5 s before the latest), `ahead`
    (120 s after it), `slow` (the answer after 6 s), `down` (HTTP 503 for `length` s
    of wall time)."""

    at: float
    kind: str
    length: float = 0.0


@dataclass
class Node:
    base: str
    config: dict[str, Any]
    frames: list[tuple[float, dict[str, Any]]]  # (scenario time of release, frame)
    faults: list[Fault] = field(default_factory=list)
    down_until: float = 0.0
    served: int = 0


class Blah2Nodes:
    """The fake nodes of every base of a deployment file that is also a scenario."""

    def __init__(self, scene: Path, seed: int = 1, speed: float = 1.0, lead: float = 0.1,
                 fc: float = 600e6, fs: float = 8e6, cpi: float = 0.25) -> None:
        self.cfg: Config = load(scene)
        scn = load_scenario(tomllib.loads(scene.read_text()))
        self.speed, self.lead, self.fc = speed, lead, fc
        self.truth: list[RadarTruth] = []
        per: dict[str, list[tuple[float, dict[str, Any]]]] = {b.id: [] for b in self.cfg.bases}
        bases = {b.id: b for b in self.cfg.bases}
        for _, out in scans(scn, self.cfg.bases, [], seed):
            for s in out:
                if isinstance(s, RadarTruth):
                    self.truth.append(s)
                elif isinstance(s, RadarScan):
                    per[s.base].append((s.t, self.frame(s, float(np.linalg.norm(bases[s.base].tx - bases[s.base].rx)))))
        assert self.cfg.origin is not None
        self.nodes = {}
        for b in self.cfg.bases:
            (rlat, rlon, ralt), (tlat, tlon, talt) = (
                (float(v) for v in self.cfg.origin.to_geodetic(p)) for p in (b.rx, b.tx))
            conf = {"capture": {"fc": fc, "fs": fs, "type": "fake"}, "process": {"data": {"cpi": cpi}},
                    "location": {"rx": {"latitude": rlat, "longitude": rlon, "altitude": ralt, "name": "rx"},
                                 "tx": {"latitude": tlat, "longitude": tlon, "altitude": talt, "name": "tx"}}}
            self.nodes[b.id] = Node(b.id, conf, per[b.id])
        self.port = free_port()
        self.t0: float | None = None
        self._loop = asyncio.new_event_loop()
        self._runner: web.AppRunner | None = None
        self._thread = threading.Thread(target=self._loop.run_forever, daemon=True)

    def frame(self, s: RadarScan, baseline: float) -> dict[str, Any]:
        rb, vb = s.plots["rb"], s.plots["vb"]
        k = rb >= baseline
        snr = s.plots.get("snr", np.full(rb.shape, 20.0))
        return {"timestamp": int(round(EPOCH_MS + (s.t - self.lead) * 1000.0)),
                "delay": ((rb[k] - baseline) / 1000.0).tolist(),
                "doppler": (-vb[k] * self.fc / C).tolist(), "snr": np.asarray(snr)[k].tolist()}

    def url(self, base: str) -> str:
        return f"http://127.0.0.1:{self.port}/{base}"

    def now(self) -> float:
        """Scenario time of the nodes' clock (before start: the first scan's)."""
        return -np.inf if self.t0 is None else (time.monotonic() - self.t0) * self.speed

    def released(self, node: Node) -> list[dict[str, Any]]:
        now = self.now()
        out = [f for t, f in node.frames if t <= now]
        return out or node.frames[:1] and [node.frames[0][1]]

    async def detection(self, request: web.Request) -> web.Response:
        node = self.nodes[request.match_info["base"]]
        if time.monotonic() < node.down_until:
            return web.Response(status=503)
        latest = dict(self.released(node)[-1])
        if node.faults and node.faults[0].at <= self.now():
            fault = node.faults.pop(0)
            if fault.kind == "json":
                return web.Response(text="{not json", content_type="application/json")
            if fault.kind == "down":
                node.down_until = time.monotonic() + fault.length
                return web.Response(status=503)
            if fault.kind == "slow":
                await asyncio.sleep(6.0)
            changes = {"lengths": {"delay": latest["delay"] + [1.0]},
                       "nan": {"doppler": latest["doppler"] + [float("nan")], "delay": latest["delay"] + [1.0],
                               "snr": latest["snr"] + [20.0]},
                       "negative": {"delay": [-1.0], "doppler": [0.0], "snr": [20.0]},
                       "back": {"timestamp": latest["timestamp"] - 5000},
                       "ahead": {"timestamp": latest["timestamp"] + 120000}}
            latest.update(changes.get(fault.kind, {}))
        node.served += 1
        return web.Response(text=json.dumps(latest), content_type="application/json")

    async def stash(self, request: web.Request) -> web.Response:
        node = self.nodes[request.match_info["base"]]
        if time.monotonic() < node.down_until:
            return web.Response(status=503)
        frames = self.released(node)
        newest = frames[-1]["timestamp"]
        keep = [f for f in frames if newest - f["timestamp"] <= STASH_S * 1000]
        rows = [(f["timestamp"], d, v) for f in keep for d, v in zip(f["delay"], f["doppler"])]
        return web.json_response({"timestamp": [r[0] for r in rows], "delay": [r[1] for r in rows],
                                  "doppler": [r[2] for r in rows]})

    async def config(self, request: web.Request) -> web.Response:
        return web.json_response(self.nodes[request.match_info["base"]].config)

    async def _start(self) -> None:
        app = web.Application()
        app.router.add_get("/{base}/api/detection", self.detection)
        app.router.add_get("/{base}/stash/detection", self.stash)
        app.router.add_get("/{base}/api/config", self.config)
        self._runner = web.AppRunner(app)
        await self._runner.setup()
        await web.TCPSite(self._runner, "127.0.0.1", self.port).start()

    def __enter__(self) -> "Blah2Nodes":
        self._thread.start()
        asyncio.run_coroutine_threadsafe(self._start(), self._loop).result(10)
        return self

    def start(self) -> None:
        """Start the nodes' clock: scan time 0 now."""
        self.t0 = time.monotonic()

    def __exit__(self, *_: Any) -> None:
        if self._runner is not None:
            asyncio.run_coroutine_threadsafe(self._runner.cleanup(), self._loop).result(10)
        self._loop.call_soon_threadsafe(self._loop.stop)
        self._thread.join(5)

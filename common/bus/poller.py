"""HTTP polling of a node on a thread of its own (aiohttp): its answers go to the
service loop as items, so that parsing, checks and counters stay on the loop."""

from __future__ import annotations

import asyncio
import threading
import time
from collections.abc import Callable, Iterable

import aiohttp

Put = Callable[[bytes], None]


class NodePoller(threading.Thread):
    """Fetches `config_path` until it answers (to `on_config`), then every `interval` s
    `latest_path` (to `on_latest`); after an outage `stash_path` first (to `on_stash`).
    A request that fails, returns a status other than 200, or takes more than `timeout`
    s puts its reason (`timeout` / `unreachable`: what) to `on_down`."""

    def __init__(self, url: str, interval: float, timeout: float, on_config: Put, on_latest: Put,
                 on_stash: Put, on_down: Put, paths: tuple[str, str, str] = (
                     "/api/config", "/api/detection", "/stash/detection")) -> None:
        super().__init__(daemon=True, name="node-poller")
        self.url, self.interval, self.timeout = url.rstrip("/"), interval, timeout
        self.on_config, self.on_latest, self.on_stash, self.on_down = on_config, on_latest, on_stash, on_down
        self.paths = paths
        self._stop_event = threading.Event()

    def stop(self) -> None:
        self._stop_event.set()

    def run(self) -> None:
        asyncio.run(self._loop())

    async def _get(self, s: aiohttp.ClientSession, path: str) -> bytes | None:
        try:
            async with s.get(self.url + path) as r:
                body = await r.read()
                if r.status != 200:
                    self.on_down(f"unreachable: {path} answered HTTP {r.status}".encode())
                    return None
                return body
        except asyncio.TimeoutError:
            self.on_down(f"timeout: {path} took more than {self.timeout:g} s".encode())
        except (aiohttp.ClientError, OSError) as e:
            self.on_down(f"unreachable: {path}: {e}".encode())
        return None

    async def _loop(self) -> None:
        config, latest, stash = self.paths
        async with aiohttp.ClientSession(timeout=aiohttp.ClientTimeout(total=self.timeout)) as s:
            got_config, down = False, False
            while not self._stop_event.is_set():
                start = time.monotonic()
                if not got_config:
                    body = await self._get(s, config)
                    if body is not None:
                        got_config = True
                        self.on_config(body)
                else:
                    body = await self._get(s, latest)
                    if body is None:
                        down = True
                    else:
                        if down and (st := await self._get(s, stash)) is not None:
                            self.on_stash(st)
                            down = False
                        self.on_latest(body)
                await asyncio.sleep(max(0.0, self.interval - (time.monotonic() - start)))


def paced(items: Iterable[tuple[float, bytes]], put: Put, speed: float, stop: threading.Event) -> None:
    """Put (t, item) in order, `speed` times real time by their t (0: at once)."""
    t0 = w0 = None
    for t, item in items:
        if stop.is_set():
            return
        if speed > 0:
            t0, w0 = (t, time.monotonic()) if t0 is None else (t0, w0)
            assert w0 is not None
            wait = w0 + (t - t0) / speed - time.monotonic()
            if wait > 0:
                time.sleep(wait)
        put(item)

"""View benchmark: the server cost of ``pfusion view`` per update with 1, 10 and 50
connected pages and 300 global tracks.

A real ``pfusion router`` and ``pfusion view`` run as child processes on loopback; this
process publishes ``radar/gtracks`` messages of 300 moving tracks at ``--rate`` Hz for
``--seconds`` s per case and connects the pages: aiohttp WebSocket clients that ack each
message at once, as the page does after drawing it (they parse only the message time).
Reported per case: the view's CPU time (user + system, /proc) per published update, the
messages and bytes each page got, the latency from put to page (p50, p99), the updates
the view took in.

Each case also has one stalled page, which opens its WebSocket and never reads.

Goals (exit code 1 if one fails): the view takes in every published update whatever
the number of pages (its Zenoh side never waits for a page), every page ends on the
last published update (the coalesced stream always delivers the latest state), and the
stalled page was sent one message only (nothing queued for it).

Run: .venv/bin/python benchmarks/view.py [--rate HZ] [--seconds S] [--pages 1 10 50]
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import re
import socket
import sys
import time
import urllib.request
from pathlib import Path
from typing import Any

import aiohttp
import numpy as np

from common.bus.procs import Child, start_router
from common.bus.transport import Publisher, free_port, open_session, wait_port
from common.deploy.config import ZenohConfig
from common.wire import protocol

ROOT = "pf/v1"
TRACKS = 300
T_RE = re.compile(rb'"gtracks":\{"t":([0-9.]+)')


def gtracks(t: float, rng: np.random.Generator, start: np.ndarray) -> bytes:
    """300 tracks on straight lines at 200 m/s, each with its covariance."""
    P = np.diag([2500.0, 4.0, 2500.0, 4.0, 1e6, 1.0]).ravel()
    tracks = [{"id": i, "status": "confirmed", "x": [x + 200.0 * t, 200.0, y - 50.0 * t, -50.0, 9000.0, 0.0],
               "P": P, "score": 10.0, "etracks": [["b1", i], ["b2", i]], "ambiguous": False}
              for i, (x, y) in enumerate(start)]
    return protocol.encode({"v": protocol.VERSION, "t": t, "tracks": tracks})


def cpu_s(pid: int) -> float:
    """User + system CPU seconds of a process (/proc/<pid>/stat fields 14, 15)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def view_stats(port: int) -> dict[str, Any]:
    with urllib.request.urlopen(f"http://127.0.0.1:{port}/stats", timeout=10) as r:
        return json.loads(r.read())


class Page:
    """One page: receives, notes the update's time and arrival, acks."""

    def __init__(self) -> None:
        self.messages = 0
        self.bytes = 0
        self.last_t = -1.0
        self.arrivals: list[tuple[float, float]] = []

    async def run(self, session: aiohttp.ClientSession, port: int, ready: asyncio.Event) -> None:
        async with session.ws_connect(f"http://127.0.0.1:{port}/ws", max_msg_size=0) as ws:
            ready.set()
            async for msg in ws:
                if msg.type != aiohttp.WSMsgType.TEXT:
                    break
                now = time.monotonic()
                data = msg.data.encode()
                self.messages += 1
                self.bytes += len(data)
                m = T_RE.search(data, 0, 200)
                if m:
                    self.last_t = float(m.group(1))
                    self.arrivals.append((self.last_t, now))
                await ws.send_str("ack")


def payloads(n: int, t0: float) -> list[bytes]:
    """n updates of message time t0, t0 + 1, ... (one scan a second)."""
    rng = np.random.default_rng(1)
    start = rng.uniform(-1e5, 1e5, size=(TRACKS, 2))
    return [gtracks(t0 + k, rng, start) for k in range(n)]


def publish(pub: Publisher, rate: float, payloads: list[bytes], t0: float,
            sent: dict[float, float]) -> None:
    """Put the updates at ``rate`` Hz, noting when each went out."""
    wall0 = time.monotonic()
    for k, p in enumerate(payloads):
        delay = wall0 + k / rate - time.monotonic()
        if delay > 0:
            time.sleep(delay)
        sent[t0 + k] = time.monotonic()
        pub.put(p)


def stalled_page(port: int) -> socket.socket:
    """A page that opens its WebSocket and then never reads nor acks."""
    s = socket.create_connection(("127.0.0.1", port))
    s.sendall(b"GET /ws HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
              b"Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n")
    return s


async def case(pub: Publisher, pid: int, port: int, pages: int, rate: float, seconds: float,
               t0: float) -> dict[str, Any]:
    stalled = stalled_page(port)
    async with aiohttp.ClientSession() as http:
        ps = [Page() for _ in range(pages)]
        ready = [asyncio.Event() for _ in ps]
        tasks = [asyncio.create_task(p.run(http, port, r)) for p, r in zip(ps, ready)]
        await asyncio.wait_for(asyncio.gather(*(r.wait() for r in ready)), 60)
        updates = payloads(int(rate * seconds), t0)
        await asyncio.sleep(1.0)
        in0, cpu0 = view_stats(port).get("in", 0), cpu_s(pid)
        sent: dict[float, float] = {}
        before = [(p.messages, p.bytes) for p in ps]
        await asyncio.to_thread(publish, pub, rate, updates, t0, sent)
        last = t0 + len(updates) - 1
        deadline = time.monotonic() + 30
        while any(p.last_t < last for p in ps) and time.monotonic() < deadline:
            await asyncio.sleep(0.1)
        cpu = cpu_s(pid) - cpu0
        after = view_stats(port)
        taken = after.get("in", 0) - in0
        stalled.close()
        for t in tasks:
            t.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)
    n = len(sent)
    lat = np.array([(now - sent[t]) * 1e3 for p in ps for t, now in p.arrivals if t in sent])
    msgs = [p.messages - b[0] for p, b in zip(ps, before)]
    return {"pages": pages, "published": n, "taken": taken, "cpu_ms": 1e3 * cpu / n,
            "cpu_ms_msg": 1e3 * cpu / max(sum(msgs), 1),
            "msgs_min": min(msgs), "msgs_mean": float(np.mean(msgs)),
            "kB_msg": sum(p.bytes - b[1] for p, b in zip(ps, before)) / max(sum(msgs), 1) / 1e3,
            "p50": float(np.percentile(lat, 50)) if lat.size else float("nan"),
            "p99": float(np.percentile(lat, 99)) if lat.size else float("nan"),
            "ended_on_last": all(p.last_t == last for p in ps),
            "stalled_msgs": min(after["page_messages"])}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rate", type=float, default=5.0, help="updates per second")
    ap.add_argument("--seconds", type=float, default=15.0, help="publishing time per case")
    ap.add_argument("--pages", type=int, nargs="+", default=[1, 10, 50])
    args = ap.parse_args()
    router, endpoint = start_router()
    port = free_port()
    view = Child("view", "view", "--connect", endpoint, "--port", str(port))
    ok = True
    try:
        wait_port(port, 60)
        with open_session(ZenohConfig([endpoint], [], ROOT)) as session:
            pub = Publisher(session, f"{ROOT}/radar/gtracks")
            while view_stats(port).get("in", 0) == 0:  # the view's subscription is in place
                pub.put(gtracks(0.0, np.random.default_rng(0), np.zeros((TRACKS, 2))))
                time.sleep(0.3)
            print(f"{TRACKS} tracks, {args.rate:g} updates/s for {args.seconds:g} s per case")
            print(f"{'pages':>5} {'published':>9} {'view in':>7} {'view CPU ms/update':>18} {'/page msg':>9} "
                  f"{'msgs/page min':>13} {'mean':>6} {'kB/msg':>7} {'p50 ms':>7} {'p99 ms':>7} last stalled")
            for k, pages in enumerate(args.pages):
                r = asyncio.run(case(pub, view.proc.pid, port, pages, args.rate, args.seconds,
                                     1000.0 * (k + 1)))
                good = r["taken"] == r["published"] and r["ended_on_last"] and r["stalled_msgs"] == 1
                ok &= good
                print(f"{r['pages']:>5} {r['published']:>9} {r['taken']:>7} {r['cpu_ms']:>18.1f} "
                      f"{r['cpu_ms_msg']:>9.2f} "
                      f"{r['msgs_min']:>13} {r['msgs_mean']:>6.1f} {r['kB_msg']:>7.1f} "
                      f"{r['p50']:>7.1f} {r['p99']:>7.1f} {'yes' if r['ended_on_last'] else ' NO'} "
                      f"{r['stalled_msgs']:>7}"
                      f"{'' if good else '  GOAL FAILED'}", flush=True)
    finally:
        view.stop()
        router.stop()
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())

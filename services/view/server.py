"""The web side of ``pfusion view``: aiohttp serves the page (files shipped in this
package's ``static/``) and one WebSocket per page, fed from the shared
:class:`~common.wire.view_model.ViewModel`.

Flow control per page (a slow browser never blocks anything else): a page's feed sends
the topics changed since its previous message, then waits for the page's ``ack`` (sent
after it has drawn the message) and ``MIN_INTERVAL_S``. At most one message per page is
in flight; while a page is slow the model keeps only the latest state per topic, so
nothing queues for it. Each topic is JSON-encoded once per version for all pages, and
frames are not compressed (permessage-deflate would compress every message again for
every page: the per-page cost would be a compression, not a socket write).
"""

from __future__ import annotations

import asyncio
import json
import time
from collections import Counter
from dataclasses import dataclass, field
from importlib.resources import files
from typing import Any

from aiohttp import WSCloseCode, WSMsgType, web

from common.wire.view_model import ViewModel

MIN_INTERVAL_S = 0.1
STALE_S = 5.0   # no data message for this long: the page says stale
ROUTER_S = 5.0  # the view without a router for this long: the page says disconnected
CLOSE_TIMEOUT_S = 1.0
STATIC = files("services.view") / "static"
CONTENT_TYPES = {".html": "text/html", ".js": "text/javascript", ".css": "text/css"}


class Hub:
    """The model plus a generation counter that page feeds wait on, and when each topic
    last changed (``received``, monotonic s): every message to a page carries each
    topic's age (``ages``, s) and the page's thresholds (``limits``), from which the page
    tells live, stale and disconnected (docs/view.md)."""

    def __init__(self, model: ViewModel, stale_s: float = STALE_S, router_s: float = ROUTER_S) -> None:
        self.model = model
        self.generation = 0
        self._changed = asyncio.Event()
        self.counters: Counter[str] = Counter()
        self.pages: set[Page] = set()
        self.limits = {"stale_s": stale_s, "router_s": router_s}
        self.received: dict[str, float] = {}
        self._versions: dict[str, int] = {}

    def bump(self) -> None:
        """The model changed: note which topics did, when, and wake every page feed."""
        now = time.monotonic()
        for name, topic in self.model.topics.items():
            if self._versions.get(name) != topic.version:
                self._versions[name] = topic.version
                self.received[name] = now
        self.generation += 1
        self._changed.set()
        self._changed = asyncio.Event()

    def extra(self) -> dict[str, Any]:
        """What a message carries beside the topics: ages of every topic now, limits."""
        now = time.monotonic()
        return {"ages": {n: round(now - t, 2) for n, t in self.received.items()},
                "limits": self.limits}

    async def wait_newer(self, generation: int) -> int:
        while self.generation == generation:
            await self._changed.wait()
        return self.generation

    def stats(self) -> dict[str, Any]:
        """Counters; per page the messages sent to it, and how many pages owe an ack."""
        return {"pages": len(self.pages), "generation": self.generation, **self.counters,
                "page_messages": sorted(p.messages for p in self.pages),
                "waiting": sum(p.waiting for p in self.pages)}


@dataclass(eq=False)
class Page:
    """One connected page: its socket and where its feed stands."""

    ws: web.WebSocketResponse
    acked: asyncio.Event = field(default_factory=asyncio.Event)
    messages: int = 0
    waiting: bool = False


async def _feed(page: Page, hub: Hub) -> None:
    """Send a page every changed topic, one message in flight at a time."""
    sent: dict[str, int] = {}
    generation = -1
    while not page.ws.closed:
        text, sent = hub.model.delta(sent, hub.extra())
        if text is not None:
            page.waiting = True
            await page.ws.send_str(text)
            page.messages += 1
            hub.counters["messages"] += 1
            hub.counters["bytes"] += len(text)
            await page.acked.wait()
            page.acked.clear()
            page.waiting = False
            await asyncio.sleep(MIN_INTERVAL_S)
            continue
        generation = await hub.wait_newer(generation)


async def websocket(request: web.Request) -> web.WebSocketResponse:
    """One page: its feed runs beside this loop, which reads the page's acks."""
    hub: Hub = request.app[HUB]
    ws = web.WebSocketResponse(heartbeat=20.0, max_msg_size=4096, compress=False,
                               timeout=CLOSE_TIMEOUT_S)
    await ws.prepare(request)
    page = Page(ws)
    hub.pages.add(page)
    feed = asyncio.create_task(_feed(page, hub))
    try:
        async for msg in ws:
            if msg.type == WSMsgType.TEXT and msg.data == "ack":
                page.acked.set()
    finally:
        hub.pages.discard(page)
        feed.cancel()
        await asyncio.gather(feed, return_exceptions=True)
    return ws


async def static(request: web.Request) -> web.Response:
    """A file of the page (index.html for /)."""
    name = request.match_info.get("name") or "index.html"
    path = STATIC / name
    suffix = "." + name.rsplit(".", 1)[-1]
    if "/" in name or suffix not in CONTENT_TYPES or not path.is_file():
        raise web.HTTPNotFound()
    return web.Response(body=path.read_bytes(), content_type=CONTENT_TYPES[suffix],
                        headers={"Cache-Control": "no-cache"})


async def stats(request: web.Request) -> web.Response:
    """The server's counters as JSON (pages, messages and bytes sent, input counters)."""
    return web.Response(text=json.dumps(request.app[HUB].stats()), content_type="application/json")


async def _close_pages(a: web.Application) -> None:
    """On shutdown: close every page's socket (a stalled one within CLOSE_TIMEOUT_S)."""
    await asyncio.gather(*(ws.close(code=WSCloseCode.GOING_AWAY, message=b"view stopped")
                           for ws in [p.ws for p in a[HUB].pages]), return_exceptions=True)


HUB = web.AppKey("hub", Hub)  # the application's one hub


def app(hub: Hub) -> web.Application:
    a = web.Application()
    a[HUB] = hub
    a.on_shutdown.append(_close_pages)
    a.add_routes([web.get("/", static), web.get("/ws", websocket), web.get("/stats", stats),
                  web.get("/{name}", static)])
    return a

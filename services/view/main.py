"""``pfusion view``: the live operator view in a browser (docs/view.md).

One Zenoh session and one subscriber per key group feed one
:class:`~common.wire.view_model.ViewModel`; every connected page gets a bounded,
coalesced stream of it over a WebSocket (services/view/server.py). The Zenoh callbacks
only append to an inbox and wake the event loop. Liveliness and counters are read as
``pfusion status`` reads them (common.bus.liveliness: ``alive``, ``take``).

``/tracks.geojson`` serves the model's global tracks as RFC 7946 GeoJSON
(common.wire.geojson) for map tools (QGIS: a vector layer on that URL, refreshed). The
page's catch-all ``/{name}`` route of server.py comes first in the router, so this
route is a middleware here.

Why aiohttp: one well-kept asyncio library that serves both HTTP and WebSockets, with
back-pressure on a WebSocket's writes; the standard library has no WebSocket server.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import logging
import signal
import sys
import time
from typing import Any

import zenoh
from aiohttp import web

from common.bus.liveliness import alive, take
from common.bus.transport import Envelope, Inbox, open_session
from common.cli import add_common, load_config
from common.deploy.config import ConfigError
from common.wire import protocol
from common.wire.geojson import collection, site_features, track_features, view_shapes
from common.wire.gtracks_union import GtracksUnion, partition_of
from common.wire.view_model import ViewModel
from services.view.access import Access, is_loopback, read_token
from services.view.server import STALE_S, Hub, app

ALIVE_PERIOD_S = 1.0
LATEST_ONLY = {"gtracks", "etracks", "truth_radar", "tma", "truth_sonar"}
GEOJSON_PATH = "/tracks.geojson"
KEYS = ("radar/gtracks", "radar/gtracks/*", "radar/etracks/*", "sim/truth/*", "sim/status", "sonar/detections/*",
        "sonar/btracks/*", "sonar/tma/*")
log = logging.getLogger("view")


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_common(p, config_required=False)
    p.add_argument("--port", type=int, default=8080, help="HTTP port of the page (0: any free one)")
    p.add_argument("--stale", type=float, default=STALE_S, metavar="S",
                   help="the page says stale after S s without a data message (default %(default)s)")
    p.add_argument("--host", default="127.0.0.1",
                   help="address to listen on (default loopback only; 0.0.0.0 for every interface, "
                        "which needs --token-file)")
    p.add_argument("--token-file", metavar="FILE",
                   help="a file (mode 600) holding the token every request must carry; required "
                        "off loopback (docs/security.md, the view)")
    p.add_argument("--allow-origin", action="append", default=[], metavar="ORIGIN",
                   help="another origin allowed to open the WebSocket, e.g. "
                        "https://view.example (repeatable; the view's own are always allowed)")


class Feed:
    """Zenoh samples -> inboxes -> the model, on the event loop."""

    def __init__(self, session: zenoh.Session, hub: Hub, root: str,
                 loop: asyncio.AbstractEventLoop) -> None:
        self.session, self.hub, self.root, self.loop = session, hub, root, loop
        self.data, self.metrics_inbox = Inbox(), Inbox()
        self.gtracks = GtracksUnion(())
        self.metrics: dict[tuple[str, str], dict[str, Any]] = {}
        self.wake = asyncio.Event()
        self.subs = [session.declare_subscriber(f"{root}/{k}", self._on_data) for k in KEYS]
        self.subs.append(session.declare_subscriber(f"{root}/metrics/**", self._on_metrics))

    def _on_data(self, sample: zenoh.Sample) -> None:
        self.data.on_sample(sample)
        self.loop.call_soon_threadsafe(self.wake.set)

    def _on_metrics(self, sample: zenoh.Sample) -> None:
        self.metrics_inbox.on_sample(sample)
        self.loop.call_soon_threadsafe(self.wake.set)

    async def pump(self) -> None:
        """Decode and ingest what was received, then wake the pages. Of a key whose
        latest message replaces the previous one (LATEST_ONLY) only the last received is
        decoded; the others are counted as ``coalesced`` (a view that falls behind skips
        them instead of lagging further)."""
        counters = self.hub.counters
        while True:
            await self.wake.wait()
            self.wake.clear()
            batch: dict[str | int, tuple[str, Envelope]] = {}
            while (env := self.data.get(0.0)) is not None:
                counters["in"] += 1
                kind = protocol.kind_of(env.key, self.root)
                if kind is None:  # KEYS name only v1 data keys
                    continue
                slot: str | int = env.key if kind in LATEST_ONLY else counters["in"]
                counters["coalesced"] += slot in batch
                batch[slot] = (kind, env)
            for kind, env in batch.values():
                self._ingest(kind, env)
            take(self.metrics_inbox, self.metrics)
            self.hub.model.set_metrics(self.metrics, time.monotonic())
            self.hub.bump()

    def _ingest(self, kind: str, env: Envelope) -> None:
        try:
            msg = protocol.decode(kind, env.payload)
            if kind == "sim_status":
                self.hub.model.sim_status(msg, time.monotonic())
            elif kind == "gtracks":  # a partition's own tracks: the union of all (docs/networks.md)
                self.hub.model.ingest(kind, self.gtracks.latest(partition_of(env.key, self.root), msg))
            else:
                self.hub.model.ingest(kind, msg)
        except ValueError as e:  # DecodeError, or a base the deployment lacks
            n = self.hub.counters["rejected"] = self.hub.counters["rejected"] + 1
            if n <= 10 or n % 1000 == 0:  # the first ones, then one in 1000
                log.error("rejected %s (%d so far): %s", env.key, n, e)

    async def watch_alive(self) -> None:
        """The liveliness tokens and whether the session has a router, every
        ALIVE_PERIOD_S (a killed service's row turns red). Without a router the tokens
        are unknown, not gone: the rows keep their last state (the page says
        disconnected)."""
        while True:
            router = await asyncio.to_thread(lambda: bool(list(self.session.info.routers_zid())))
            self.hub.model.set_link(router)
            if router:
                live = await asyncio.to_thread(alive, self.session, self.root)
                self.hub.model.set_alive(set(live), time.monotonic())
            self.hub.bump()
            await asyncio.sleep(ALIVE_PERIOD_S)

    def close(self) -> None:
        for s in self.subs:
            s.undeclare()


def tracks_geojson(model: ViewModel) -> dict[str, Any] | None:
    """The sites and global tracks of the model as a FeatureCollection (None: the
    deployment has no [radar.origin])."""
    origin = model.cfg.origin
    if origin is None:
        return None
    topic = model.topics.get("gtracks")
    state = topic.state if topic is not None else {"t": 0.0, "tracks": []}
    return collection(site_features(model.cfg, origin) + track_features(view_shapes(state), origin))


def geojson_route(model: ViewModel) -> Any:
    """The middleware that answers GET GEOJSON_PATH."""

    @web.middleware
    async def route(request: web.Request, handler: Any) -> web.StreamResponse:
        if request.path != GEOJSON_PATH or request.method != "GET":
            return await handler(request)
        doc = tracks_geojson(model)
        if doc is None:
            raise web.HTTPNotFound(text="no [radar.origin] in the deployment: no geographic positions")
        return web.Response(text=json.dumps(doc, separators=(",", ":")), content_type="application/geo+json",
                            headers={"Cache-Control": "no-cache"})

    return route


async def serve(args: argparse.Namespace, session: zenoh.Session, model: ViewModel, root: str,
                token: str | None = None) -> int:
    loop = asyncio.get_running_loop()
    stop = asyncio.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        loop.add_signal_handler(sig, stop.set)
    hub = Hub(model, stale_s=args.stale)
    feed = Feed(session, hub, root, loop)  # subscribed before the page can be reached
    application = app(hub)
    access = Access(token, args.allow_origin, hub.counters)
    application.middlewares.append(access.middleware())  # first: it guards every route
    application.middlewares.append(geojson_route(model))
    runner = web.AppRunner(application, access_log=None, shutdown_timeout=2.0)
    await runner.setup()
    site = web.TCPSite(runner, args.host, args.port)
    try:
        await site.start()
    except OSError as e:
        feed.close()
        await runner.cleanup()
        print(f"pfusion view: cannot listen on {args.host}:{args.port} ({e.strerror}): "
              "pass --port with a free port", file=sys.stderr)
        return 2
    port = runner.addresses[0][1]
    access.listening(args.host, port)
    print(f"view: http://{args.host}:{port}/" + (f" (open /?token=<the token in {args.token_file}> "
                                                 "once)" if token else ""), flush=True)
    tasks = [asyncio.create_task(feed.pump()), asyncio.create_task(feed.watch_alive())]
    try:
        await stop.wait()
    finally:
        feed.close()
        for t in tasks:
            t.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)
        await runner.cleanup()
    log.info("stopped: %s", hub.stats())
    return 0


def main(args: argparse.Namespace) -> int:
    cfg = load_config(args)
    token = read_token(args.token_file) if args.token_file else None
    if token is None and not is_loopback(args.host):
        raise ConfigError("--token-file", f"a view listening on {args.host} (not loopback) needs "
                                          "a token: --token-file FILE (mode 600, docs/security.md)")
    with open_session(cfg.zenoh) as session:
        return asyncio.run(serve(args, session, ViewModel(cfg), cfg.zenoh.root, token))

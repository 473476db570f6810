"""Who may use ``pfusion view`` (docs/security.md, "The view"): an Origin allow-list on
the WebSocket, always, and a token when the view listens on anything but loopback.

Origin: a browser sends the page's origin with every WebSocket handshake; one not in
the allow-list (a page of another site trying to read the picture through the
operator's browser, or a DNS-rebound name) is refused with 403 and counted
(``refused_origin``). The default list is the view's own origins on the address it
listens on (for loopback: 127.0.0.1, localhost, [::1]; for every interface: those, the
host's name, its fully qualified name and their addresses), each with the port;
``--allow-origin`` adds others (a reverse proxy's). A handshake without Origin does not
come from a browser page and is not checked (it could not be a cross-site request).

Token: off loopback, every request needs the token of ``--token-file`` (a file only its
owner may read: a group- or world-readable one is refused, exit 2). The first load
carries it in the query (``http://host:8080/?token=T``); the view answers with a
redirect to ``/`` that sets it as a cookie (HttpOnly, SameSite=Strict), which the page's
own requests and WebSocket then carry; tools send ``Authorization: Bearer T``. A
missing or wrong token is refused with 401 and counted (``refused_token``).
"""

from __future__ import annotations

import hmac
import ipaddress
import socket
from collections import Counter
from pathlib import Path
from typing import Any

from aiohttp import web

from common.deploy.config import ConfigError

COOKIE = "pfusion_view_token"
LOOPBACK_NAMES = ("127.0.0.1", "localhost", "[::1]")


def is_loopback(host: str) -> bool:
    """Whether ``host`` (a --host value) is a loopback address or name."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


def read_token(path: str) -> str:
    """The token in ``path`` (first line), refused when group or others may read or
    write the file, or when it is empty (ConfigError: exit 2)."""
    p = Path(path)
    if not p.is_file():
        raise ConfigError("--token-file", f"{path} does not exist")
    mode = p.stat().st_mode & 0o777
    if mode & 0o077:
        raise ConfigError("--token-file", f"{path} may be read or written by group or others "
                                          f"(mode {mode:o}): chmod 600 {path}")
    token = (p.read_text().splitlines() or [""])[0].strip()
    if len(token) < 16:
        raise ConfigError("--token-file", f"{path} holds no token of at least 16 characters "
                                          "(e.g. openssl rand -hex 16)")
    return token


def _names(host: str) -> set[str]:
    """The names and addresses a browser may use for a view listening on ``host``."""
    if is_loopback(host):
        return set(LOOPBACK_NAMES)
    if host not in ("0.0.0.0", "::", ""):
        return {f"[{host}]" if ":" in host else host}
    names = {*LOOPBACK_NAMES, socket.gethostname(), socket.getfqdn()}
    for name in list(names):
        try:
            infos = socket.getaddrinfo(name.strip("[]"), None)
        except OSError:
            continue
        names |= {f"[{i[4][0]}]" if ":" in str(i[4][0]) else str(i[4][0]) for i in infos}
    return names


def default_origins(host: str, port: int) -> set[str]:
    """The view's own origins when it listens on ``host``:``port``."""
    return {f"http://{name}:{port}" for name in _names(host)}


class Access:
    """The allow-list (filled once the port is known), the token (None: not required)
    and the refusal counters (shown by /stats)."""

    def __init__(self, token: str | None, extra_origins: list[str], counters: Counter[str]) -> None:
        self.token = token
        self.origins: set[str] = {o.rstrip("/") for o in extra_origins}
        self.counters = counters

    def listening(self, host: str, port: int) -> None:
        self.origins |= default_origins(host, port)

    def _token_ok(self, request: web.Request) -> bool:
        if self.token is None:
            return True
        auth = request.headers.get("Authorization", "")
        given = request.cookies.get(COOKIE) or (auth[7:] if auth.startswith("Bearer ") else "")
        return hmac.compare_digest(given.encode(), self.token.encode())

    def middleware(self) -> Any:
        @web.middleware
        async def check(request: web.Request, handler: Any) -> web.StreamResponse:
            if self.token is not None and "token" in request.query:
                if not hmac.compare_digest(request.query["token"].encode(), self.token.encode()):
                    self.counters["refused_token"] += 1
                    raise web.HTTPUnauthorized(text="wrong token")
                response = web.HTTPFound("/")
                response.set_cookie(COOKIE, self.token, httponly=True, samesite="Strict", path="/")
                raise response
            if not self._token_ok(request):
                self.counters["refused_token"] += 1
                raise web.HTTPUnauthorized(text="this view needs its token: open "
                                                "/?token=TOKEN once (docs/security.md)")
            origin = request.headers.get("Origin")
            if request.path == "/ws" and origin is not None and origin not in self.origins:
                self.counters["refused_origin"] += 1
                raise web.HTTPForbidden(text=f"origin {origin} is not allowed (--allow-origin)")
            return await handler(request)

        return check

"""``pfusion view``'s access checks (services/view/access.py, docs/security.md "The
view") with real HTTP and WebSocket requests (aiohttp's client) to a real view process
on a real router.

On loopback (the default): the view's own origins open the WebSocket, a foreign origin
or another port is refused (403) and counted; no token is needed. Listening on every
interface: no token file, or one that others may read, is exit 2; every request without
the token is refused (401) and counted; the first load with ``?token=`` sets the cookie
the page's requests and WebSocket then carry; a foreign origin is still refused with
it. tests/integration/test_view.py (Chromium) shows the page still works on loopback.
Time: about 6 s."""

from __future__ import annotations

import asyncio
import secrets
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import aiohttp
import pytest

from common.bus.procs import Child, start_router
from common.bus.transport import free_port, wait_port
from tests.harness import SCENARIOS

TWO_TARGETS = SCENARIOS / "two_targets.toml"


@pytest.fixture(scope="module")
def router(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    child, endpoint = start_router(tmp_path_factory.mktemp("router") / "router.log")
    try:
        yield endpoint
    finally:
        child.stop()


def view(endpoint: str, log: Path, *args: str) -> Child:
    return Child("view", "view", "--config", str(TWO_TARGETS), "--connect", endpoint, *args, log=log)


async def handshake(url: str, origin: str | None, session: aiohttp.ClientSession | None = None) -> int:
    """The status of a WebSocket handshake (101 when it opened)."""
    headers = {"Origin": origin} if origin else {}
    own = session is None
    s = session or aiohttp.ClientSession()
    try:
        async with s.ws_connect(url, headers=headers):
            return 101
    except aiohttp.WSServerHandshakeError as e:
        return e.status
    finally:
        if own:
            await s.close()


async def stats(base: str, **kw: Any) -> dict[str, Any]:
    async with aiohttp.ClientSession() as s, s.get(f"{base}/stats", **kw) as r:
        assert r.status == 200
        return dict(await r.json())


def test_loopback_view_allows_its_own_origins_only(router: str, tmp_path: Path) -> None:
    port = free_port()
    v = view(router, tmp_path / "view.log", "--port", str(port))
    try:
        wait_port(port, timeout=60.0)
        base, ws = f"http://127.0.0.1:{port}", f"ws://127.0.0.1:{port}/ws"

        async def check() -> tuple[list[int], dict[str, Any]]:
            codes = [await handshake(ws, o) for o in (
                base, f"http://localhost:{port}", None, "http://evil.example",
                f"http://127.0.0.1:{port + 1}", "null")]
            return codes, await stats(base)

        codes, counters = asyncio.run(check())
    finally:
        v.stop()
    assert codes == [101, 101, 101, 403, 403, 403], (tmp_path / "view.log").read_text()
    assert counters["refused_origin"] == 3 and counters.get("refused_token", 0) == 0


def test_view_off_loopback_needs_its_token(router: str, tmp_path: Path) -> None:
    token = secrets.token_hex(16)
    tok = tmp_path / "token"
    tok.write_text(token + "\n")
    tok.chmod(0o644)
    port = free_port()
    args = ("--host", "0.0.0.0", "--port", str(port))
    for extra, name in (((), "no-file"), (("--token-file", str(tok)), "readable")):
        refused = view(router, tmp_path / f"{name}.log", *args, *extra)
        assert refused.wait(60) == 2, name
        assert "--token-file" in (tmp_path / f"{name}.log").read_text(), name
    assert "chmod 600" in (tmp_path / "readable.log").read_text()
    tok.chmod(0o600)
    v = view(router, tmp_path / "view.log", *args, "--token-file", str(tok))
    try:
        wait_port(port, timeout=60.0)
        base, ws = f"http://127.0.0.1:{port}", f"ws://127.0.0.1:{port}/ws"

        async def check() -> dict[str, Any]:
            out: dict[str, Any] = {}
            async with aiohttp.ClientSession() as anon:
                out["anon"] = [(await anon.get(f"{base}{path}")).status
                               for path in ("/", "/stats", "/view.js", "/tracks.geojson",
                                            "/?token=wrong")]
                out["anon_ws"] = await handshake(ws, base, anon)
            async with aiohttp.ClientSession(cookie_jar=aiohttp.CookieJar(unsafe=True)) as page:
                first = await page.get(f"{base}/?token={token}", allow_redirects=False)
                out["first"] = (first.status, first.headers.get("Location"),
                                first.cookies.get("pfusion_view_token") is not None)
                again = await page.get(f"{base}/")
                out["page"] = (again.status, "<html" in (await again.text()).lower())
                out["ws"] = [await handshake(ws, o, page) for o in (base, "http://evil.example")]
            out["stats"] = await stats(base, headers={"Authorization": f"Bearer {token}"})
            return out

        out = asyncio.run(check())
    finally:
        v.stop()
    log = (tmp_path / "view.log").read_text()
    assert out["anon"] == [401] * 5 and out["anon_ws"] == 401, log
    assert out["first"] == (302, "/", True) and out["page"] == (200, True)
    assert out["ws"] == [101, 403]
    assert out["stats"]["refused_token"] == 6 and out["stats"]["refused_origin"] == 1
    assert token not in log  # the token is a credential: never in the output

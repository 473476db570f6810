"""``pfusion status``: live services from liveliness tokens, with their latest counters."""

from __future__ import annotations

import signal
import subprocess
import time
from pathlib import Path

import pytest

from common.bus.procs import pfusion_argv
from services.status.main import table
from tests.harness import ROOT, SCENARIOS, Deployment

TWO_TARGETS = SCENARIOS / "two_targets.toml"


def status(endpoint: str, *extra: str) -> dict[tuple[str, str], list[str]]:
    """Rows of ``pfusion status`` by (service, instance)."""
    out = subprocess.run(pfusion_argv("status", "--connect", endpoint, *extra),
                         capture_output=True, text=True, timeout=30, check=True).stdout
    lines = out.splitlines()
    assert lines[0].split() == ["service", "instance", "in", "out", "rejected", "missed",
                                "p50_ms", "p99_ms", "queue", "last_t"]
    return {(r[0], r[1]): r[2:] for r in (line.split() for line in lines[1:])}


def test_table_layout() -> None:
    metrics = {("svc", "a"): {"in": 12, "out": 3, "rejected": {"decode:rb": 2, "unknown_base": 1},
                              "missed": {"pf/v1/radar/plots/b1/c1": 4, "pf/v1/radar/plots/b1/c2": 1},
                              "p50_ms": 0.123, "p99_ms": 1.5, "queue": 0, "t": 42.0}}
    lines = table([("other", "x"), ("svc", "a")], metrics).splitlines()
    assert lines[1].split() == ["other", "x", "-", "-", "-", "-", "-", "-", "-", "-"]
    assert lines[2].split() == ["svc", "a", "12", "3", "3", "5", "0.12", "1.50", "0", "42.000",
                                "decode:rb=2,", "unknown_base=1"]
    second = {line.index(line.split()[1], len(line.split()[0])) for line in lines}
    assert second == {len("service") + 2}


@pytest.mark.slow
def test_status_lists_live_services_with_their_counters(tmp_path: Path) -> None:
    with Deployment(tmp_path) as d:
        d.start("plotter", "channel-plotter", "--config", str(TWO_TARGETS), "--base", "b1")
        d.collect("sim/status")
        d.wait_alive(["channel_plotter/b1"])
        d.session.put(f"{ROOT}/radar/plots/b1/c1", b"\xc1 not msgpack")
        d.simulate(TWO_TARGETS, wait_alive=["channel_plotter/b1"])
        deadline = time.monotonic() + 20
        while True:
            rows = status(d.endpoint)
            plotter = rows.get(("channel_plotter", "b1"))
            if plotter and plotter[0] == "361" or time.monotonic() > deadline:
                break
        assert rows[("test", "collector")] == ["-"] * 8
        assert ("simulate", "two_targets") not in rows
        assert plotter is not None
        n_in, n_out, rejected, missed, p50, p99, queue, last_t, *reasons = plotter
        assert (n_in, rejected, missed, queue) == ("361", "1", "0", "0")
        assert int(n_out) >= 120
        assert 0 < float(p50) <= float(p99)
        d.wait_for(lambda: bool(d.of("sim/status")))
        assert float(last_t) == d.of("sim/status")[0]["t"]
        assert reasons == ["decode:<payload>=1"]


def test_status_watch_refreshes_until_interrupted(tmp_path: Path) -> None:
    with Deployment(tmp_path) as d:
        d.announce()
        proc = subprocess.Popen(pfusion_argv("status", "--connect", d.endpoint, "--watch"),
                                stdout=subprocess.PIPE, text=True)
        assert proc.stdout is not None
        headers = []
        for line in proc.stdout:
            if "live under" in line:
                headers.append(line)
                if len(headers) == 2:
                    break
        proc.send_signal(signal.SIGINT)
        assert proc.wait(15) == 0
        assert all(h.split()[1:] == ["1", "live", "under", ROOT] for h in headers)

"""``pfusion status``: live services from liveliness tokens, with their latest counters."""

from __future__ import annotations

import signal
import subprocess
import time
from pathlib import Path

import pytest

from common.bus.liveliness import FORGED, Drain, take
from common.bus.procs import pfusion_argv
from common.bus.transport import Envelope, Inbox, stamp
from common.deploy.config import ZenohConfig
from common.wire import protocol
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


def test_drain_needs_two_quiet_reports_from_every_expected_service(tmp_path: Path) -> None:
    """``pfusion run --exit-after-sim`` stops only once every service has drained: two
    metrics reports in a row with the same input count and an empty queue; an instance
    ``*`` is matched by any instance, and a service that never reports keeps it waiting."""
    def report(service: str, instance: str, n_in: int, queue: int = 0) -> None:
        d.session.put(f"{ROOT}/metrics/{service}/{instance}",
                      protocol.encode({"service": service, "instance": instance,
                                       "in": n_in, "queue": queue}))

    def settled() -> bool:
        time.sleep(0.3)
        return drain.drained()

    with Deployment(tmp_path) as d:
        drain = Drain(ZenohConfig([d.endpoint], [], ROOT), ["plotter/b1", "fusion/*"])
        try:
            time.sleep(0.5)
            report("plotter", "b1", 5)
            report("plotter", "b1", 5)
            drain.mark()
            report("plotter", "b1", 7)
            report("fusion", "main", 3)
            report("plotter", "b1", 7)
            report("fusion", "main", 4)
            assert not settled()  # fusion's input still grows
            report("fusion", "main", 4, queue=2)
            assert not settled()  # fusion has a backlog
            report("fusion", "main", 6)
            report("fusion", "main", 6)
            assert settled()
            report("plotter", "b1", 8)
            assert not settled()  # a later input undoes it
            drain.mark()
            report("plotter", "b1", 8)
            report("plotter", "b1", 8)
            assert not settled()  # fusion has not reported since the mark
        finally:
            drain.close()


def test_metrics_take_the_identity_of_their_key() -> None:
    """The payload on channel_plotter/b1's key that names global_fusion/main is ignored and
    counted; the true one is kept under the key's name."""
    inbox = Inbox()
    forged = {"service": "global_fusion", "instance": "main", "in": 999999}
    true = {"service": "channel_plotter", "instance": "b1", "in": 4}
    for m in (forged, true):
        inbox.put(Envelope(f"{ROOT}/metrics/channel_plotter/b1", protocol.encode(m)))
    before = FORGED[f"{ROOT}/metrics/channel_plotter/b1"]
    metrics: dict[tuple[str, str], dict[str, object]] = {}
    take(inbox, metrics)
    assert list(metrics) == [("channel_plotter", "b1")] and metrics[("channel_plotter", "b1")]["in"] == 4
    assert FORGED[f"{ROOT}/metrics/channel_plotter/b1"] == before + 1


def test_status_takes_identity_from_the_key_and_stamp_jumps_are_not_losses(tmp_path: Path) -> None:
    """A sample on the plotter's own metrics key that names global fusion is ignored (the
    key, which the ACL protects, names the service); two junk plots with forged stamps
    10^12 apart count as stamp_jump, not as 10^12 missed samples, and a real gap after
    them is still counted."""
    with Deployment(tmp_path) as d:
        d.start("plotter", "channel-plotter", "--config", str(TWO_TARGETS), "--base", "b1")
        d.wait_alive(["channel_plotter/b1"])
        forged = {"v": protocol.VERSION, "service": "global_fusion", "instance": "main", "in": 999999,
                  "out": 0, "rejected": {"invented": 1}, "missed": {}, "p50_ms": 0.0, "p99_ms": 0.0,
                  "queue": 0, "t": 0.0}
        key = f"{ROOT}/radar/plots/b1/c1"
        for n in (0, 10**12, 1, 3):  # 10^12: a jump; 3 after 1: one sample really missed
            d.session.put(key, b"\xc1 junk", attachment=stamp("forger", n))
        deadline = time.monotonic() + 20
        while True:
            d.session.put(f"{ROOT}/metrics/channel_plotter/b1", protocol.encode(forged))
            rows = status(d.endpoint)
            plotter = rows.get(("channel_plotter", "b1"))
            if plotter and plotter[0] == "4" or time.monotonic() > deadline:
                break
            time.sleep(0.3)
    assert ("global_fusion", "main") not in rows
    assert plotter is not None and plotter[0] == "4", plotter
    assert plotter[3] == "1"  # missed: the one real gap (2), not 10^12
    assert "stamp_jump=1," in plotter[8:] or "stamp_jump=1" in plotter[8:], plotter

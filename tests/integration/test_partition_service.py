"""`pfusion global-fusion --partition` on loopback (services/global_fusion, docs/networks.md
"Partitions"): a handover sent to it is adopted under its number, acked to its sender
(again for a repeated copy), and published with the partition's tracks on
radar/gtracks/<p>; a handover addressed to another partition is rejected and counted
(partition_mismatch); a partitioned file without --partition is refused (exit 2).
About 10 s."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from common.bus.procs import Child
from common.bus.transport import Publisher
from common.core.track_table import Status
from common.radar.network.partition import Handed
from common.wire import protocol
from common.wire.radar_messages import handover_message
from tests.harness import ROOT, Deployment
from tests.integration.test_partition_multihost import DEPLOY, feed

FUSION = str(DEPLOY / "fusion.toml")


def test_a_partition_adopts_acks_publishes_and_rejects(tmp_path: Path) -> None:
    etracks, _ = feed()
    first = sorted(r for rs in etracks.values() for r in rs if r[0] < 8.0)
    t_h = first[len(first) // 2][0]
    x = np.array([1e4, 0.0, 2e4, 0.0, 8e3, 0.0])  # in the east half
    h = Handed(11, int(Status.CONFIRMED), t_h, x, np.diag([1e4, 1e2, 1e4, 1e2, 1e4, 1e2]),
               t_h, 0.0, 3, (("r3dvbt8", 99),))
    refused = Child("refused", "global-fusion", "--config", FUSION, log=tmp_path / "refused.log")
    with Deployment(tmp_path) as d:
        for k in ("radar/handover_ack/*", "radar/gtracks/*", "metrics/global_fusion/*"):
            d.collect(k)
        d.start("east", "global-fusion", "--config", FUSION, "--partition", "east")
        d.wait_alive(["global_fusion/east"])
        pubs = {b: Publisher(d.session, f"{ROOT}/radar/etracks/{b}") for b in etracks}
        handover = Publisher(d.session, f"{ROOT}/radar/handover/east")
        sent = False
        for t, b, payload in first:
            if t >= t_h and not sent:
                for msg in (handover_message("west", "east", h),) * 2 + (
                        handover_message("west", "west", h),):
                    handover.put(protocol.encode(msg))
                sent = True
            pubs[b].put(payload)
            time.sleep(0.002)
        d.wait_for(lambda: len(d.of("radar/handover_ack/west")) == 2)
        assert [(a["from"], a["to"], a["id"]) for a in d.of("radar/handover_ack/west")] == \
            [("east", "west", 11)] * 2
        d.wait_for(lambda: any(k["id"] == 11 for g in d.of("radar/gtracks/east")
                               for k in g["tracks"]))
        d.wait_for(lambda: any(m["rejected"].get("partition_mismatch") == 1
                               and m["handover"]["adopted"] == 1
                               for m in d.of("metrics/global_fusion/east")))
    assert refused.wait(60.0) == 2
    assert "--partition" in (tmp_path / "refused.log").read_text()

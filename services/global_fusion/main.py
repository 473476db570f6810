"""``pfusion global-fusion``: elementary tracks of all bases -> global Cartesian tracks
(001 step 24, modules 61-65; crossing management of 004).

Subscribes radar/etracks/*, publishes radar/gtracks once per fusion cycle with every
live global track. The algorithm is common.radar.fusion.cycle; this module only decodes
and validates (into typed arrays, common.wire.radar_messages.etracks_of) and publishes.
Parameters: [radar.fusion] (FusionParams) and, optionally,
[radar.fusion_crossing] (CrossingParams); without that table the global tracks use the
sup-norm ambiguity test of 004 (dimension-free; eq. 13 needs the surveillance volume
in m^3 as `volume`). [radar.tracker] (ElementaryParams) gives the elementary trackers'
F [19] / Q [20] noise, needed to recover their equivalent measurements.

Cycle rule: a base that has sent nothing usable for `max_wait` seconds of wall time
(since its last accepted message, or since the first message of any base) is stale; the
core then runs cycles without it (common.radar.fusion.cycle says why wall time and not
message time). Rejected, counted and logged (docs/faults.md): a message whose cycle
already ran (time_backwards: late, out of order, or a base whose clock jumped back; its
base goes stale if nothing else comes), a second message of one base and time
(duplicate), and one more than `max_lead` s of message time after the latest cycle
(clock_ahead: a base whose clock jumped forward; buffering its messages until the
other bases reach their time would grow the buffer by one message per scan). A base
whose latest message was clock_ahead is stale at once, until it sends a message in
reach again (or a late one: its clock is back, the next cycle waits for it).
A late message (its cycle already ran) at most `max_wait` s of message time behind the
latest cycle still shows its base alive, so the next cycle waits for it: a stale base
whose stream runs slightly behind the others' (a site back after a cut link, issue 12)
would otherwise stay stale for as long as its messages arrive after the others'.
"""

from __future__ import annotations

import argparse
import time

from common.bus.service import Service
from common.cli import add_common, load_config
from common.core.rejection import Rejected
from common.deploy.config import ConfigError, section
from common.radar.fusion.params import FusionParams
from common.wire.radar_chain import global_fusion
from common.wire.radar_messages import etracks_of, gtracks_message


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_common(p)


def main(args: argparse.Namespace) -> int:
    cfg = load_config(args)
    params = section(cfg, "radar.fusion", FusionParams)
    try:
        core = global_fusion(cfg)
    except ValueError as e:
        raise ConfigError("radar.base", str(e)) from None
    svc = Service("global_fusion", "main", cfg)
    heard: dict[str, float] = {}  # wall time of each base's last message
    ahead: set[str] = set()  # bases whose latest message was clock_ahead

    def on_etracks(key: str, payload: bytes) -> None:
        base, tracks = etracks_of(payload)
        t = tracks.t
        if base not in core.index:
            raise Rejected("unknown_base", f"base '{base}' is not configured")
        if key.rsplit("/", 1)[-1] != base:
            raise Rejected("base_mismatch", f"base '{base}' published on {key}")
        if core.is_late(t):
            ahead.discard(base)  # its clock is back: the next cycle waits for it
            if t >= core.t_last - params.max_wait:  # just behind (docstring)
                heard[base] = time.monotonic()
            raise Rejected("time_backwards", f"t={t} after the cycle of t={core.t_last}")
        if core.is_duplicate(base, t):
            raise Rejected("duplicate", f"base '{base}' sent t={t} twice")
        now = time.monotonic()
        for b in core.base_ids:  # a base never heard of is silent since the first message
            heard.setdefault(b, now)
        heard[base] = now
        if core.t_last is not None and t > core.t_last + params.max_lead:
            ahead.add(base)
            raise Rejected("clock_ahead", f"base '{base}' t={t} is more than "
                                          f"max_lead={params.max_lead} s after the cycle of "
                                          f"t={core.t_last}: not fused, base stale")
        ahead.discard(base)
        stale = frozenset(b for b, h in heard.items() if now - h > params.max_wait) | ahead
        for out in core.push(base, tracks, stale):
            svc.last_t = out.t
            svc.publish("radar/gtracks", gtracks_message(out, cfg.origin))

    svc.subscribe("radar/etracks/*", on_etracks)
    return svc.run()

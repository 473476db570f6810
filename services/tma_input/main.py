"""``pfusion tma-input {bounds,support,clear} --config F --array A --track N [--birth T]``:
an operator's seed 003 bounds (claim 4) or seed 002 support value (claims 3-10) for one
bearing track, or their clearing, sent to ``pfusion tma --array A`` (issue 31).

The input names its track by (number, birth); without ``--birth`` the command takes the
birth of the current track of that number from the next root/sonar/tma/A message (its
``births``) and says which it used. It publishes on root/sonar/tma/{bounds,support,clear}/A
with a request id and waits for the tma service's answer on root/sonar/tma/ack/A: exit 0
when accepted, 1 when refused (the reason is printed) or unanswered within --timeout.
Runs as the Zenoh identity ``operator-tma`` (docs/security.md). Units: degrees for
courses, m/s for speeds, metres for ranges and positions, seconds of message time.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import time
import uuid
from typing import Any

import zenoh

from common.bus.transport import Inbox, open_session
from common.cli import add_common, load_config
from common.core.angles import TWO_PI, wrap_2pi
from common.core.params import ParamError
from common.deploy.sections import array_bounds
from common.sonar.tma.bearings_only import Support
from common.wire import protocol
from common.wire.sonar_messages import bounds_message, clear_message, support_message

BLOCK = zenoh.CongestionControl.BLOCK


def add_arguments(p: argparse.ArgumentParser) -> None:
    sub = p.add_subparsers(dest="op", required=True, metavar="{bounds,support,clear}")
    ops = {
        "bounds": "set one track's bounds (003 claim 4); omitted ones: the array's configured bounds",
        "support": "give one track a support value (002 claims 3-10)",
        "clear": "forget one track's operator bounds, support values or both",
    }
    for name, help_ in ops.items():
        q = sub.add_parser(name, help=help_, description=help_)
        add_common(q)
        q.add_argument("--array", required=True, help="sonar array id of the deployment")
        q.add_argument("--track", type=int, required=True, help="bearing track number (btracks id)")
        q.add_argument("--birth", type=float, help="birth of the track (s, `births` of the tma "
                                                   "message); default: the current track's")
        q.add_argument("--timeout", type=float, default=30.0,
                       help="seconds to wait for the tma message and the ack (default 30)")
    b = sub.choices["bounds"]
    for k, unit in (("range", "m"), ("course", "deg, clockwise interval min -> max"),
                    ("speed", "m/s")):
        b.add_argument(f"--{k}-min", type=float, help=f"{k} lower bound ({unit})")
        b.add_argument(f"--{k}-max", type=float, help=f"{k} upper bound ({unit})")
    s = sub.choices["support"]
    s.add_argument("--kind", required=True, choices=("range", "course", "speed"))
    s.add_argument("--value", type=float, required=True, help="m, deg or m/s by --kind")
    s.add_argument("--sigma", type=float, required=True, help="its standard deviation, same unit")
    s.add_argument("--at", type=float, help="time of the value (s); default: the latest tma message's")
    s.add_argument("--obs-x", type=float, help="East of the observing position (m), for a range")
    s.add_argument("--obs-y", type=float, help="North of the observing position (m), for a range")
    sub.choices["clear"].add_argument("--what", choices=("bounds", "support", "all"), default="all")


def fail(why: str) -> int:
    print(f"pfusion tma-input: {why}", file=sys.stderr)
    return 1


def request(args: argparse.Namespace, cfg: Any, t: float, birth: float | None, req: str) -> dict[str, Any]:
    """The message of the operation (ParamError for bounds that break their rules)."""
    if args.op == "bounds":
        given = {"r_min": args.range_min, "r_max": args.range_max, "speed_min": args.speed_min,
                 "speed_max": args.speed_max, "course_min": _rad(args.course_min),
                 "course_max": _rad(args.course_max)}
        b = dataclasses.replace(array_bounds(cfg, args.array),
                                **{k: v for k, v in given.items() if v is not None})
        return bounds_message(t, b, args.track, birth, req)
    if args.op == "support":
        value, sigma = (_rad(args.value), _rad(args.sigma)) if args.kind == "course" else (args.value, args.sigma)
        xy = (args.obs_x or 0.0, args.obs_y or 0.0)
        return support_message(args.track, Support(args.kind, value, sigma, t, xy), birth, req)
    return clear_message(t, args.track, args.what, birth, req)


def _rad(deg: float | None) -> float | None:
    """Degrees to radians, in [0, 2 pi] (360 stays 2 pi: a course interval's end)."""
    if deg is None:
        return None
    r = math.radians(deg)
    return r if 0.0 <= r <= TWO_PI else float(wrap_2pi(r))


def main(args: argparse.Namespace) -> int:
    cfg = load_config(args)
    arr = cfg.array(args.array)
    if args.op == "support" and args.kind == "range" and (args.obs_x is None or args.obs_y is None):
        return fail("a range support needs --obs-x and --obs-y (where it was observed from)")
    root = cfg.zenoh.root
    inbox = Inbox()
    deadline = time.monotonic() + args.timeout
    with open_session(cfg.zenoh) as session:
        subs = [session.declare_subscriber(f"{root}/sonar/tma/{k}", inbox.on_sample)
                for k in (arr.id, f"ack/{arr.id}")]
        birth, t = args.birth, args.at if args.op == "support" else 0.0
        if birth is None or t is None:
            latest = _next(inbox, f"{root}/sonar/tma/{arr.id}", "tma", deadline)
            if latest is None:
                return fail(f"no tma message of array {arr.id} within {args.timeout} s "
                            f"(is 'pfusion tma --array {arr.id}' running?)")
            births = {e["track"]: e["birth"] for e in latest.get("births", [])}
            t = latest["t"] if t is None else t
            if birth is None:
                if args.track not in births:
                    return fail(f"track {args.track} is not a live track of array {arr.id} at "
                                f"t={latest['t']} (live: {sorted(births)})")
                birth = births[args.track]
                print(f"track {args.track} of {arr.id}: the current one, born at t={birth} "
                      f"(tma message of t={latest['t']})", flush=True)
        req = uuid.uuid4().hex
        try:
            msg = request(args, cfg, float(t or 0.0), birth, req)
        except ParamError as e:
            return fail(f"invalid bounds: {e}")
        session.put(f"{root}/sonar/tma/{args.op}/{arr.id}", protocol.encode(msg), congestion_control=BLOCK)
        ack = _next(inbox, f"{root}/sonar/tma/ack/{arr.id}", "tma_ack", deadline, req)
        for s in subs:
            s.undeclare()
    if ack is None:
        return fail(f"no answer from tma/{arr.id} within {args.timeout} s (request {req})")
    if not ack["ok"]:
        return fail(f"refused by tma/{arr.id}: {ack['reason']} (track {args.track}, birth {birth})")
    print(f"accepted by tma/{arr.id}: {args.op} of track {ack.get('track')} born at t={ack.get('birth')}")
    return 0


def _next(inbox: Inbox, key: str, kind: str, deadline: float, req: str | None = None) -> dict[str, Any] | None:
    """The next valid message on ``key`` (with request id ``req``), None at the deadline;
    other keys' messages are left aside."""
    while time.monotonic() < deadline:
        env = inbox.get(0.1)
        if env is None or env.key != key:
            continue
        try:
            msg = protocol.decode(kind, env.payload)
        except protocol.DecodeError as e:
            print(f"pfusion tma-input: invalid {kind} message ignored: {e}", file=sys.stderr)
            continue
        if req is None or msg["req"] == req:
            return msg
    return None

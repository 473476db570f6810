"""Userspace netem: bridge the frames of two interfaces with a delay, jitter and loss,
like ``tc qdisc add dev X root netem delay D J loss L`` on both bridge ports.

Used by tests/netns.py where the kernel has no ``sch_netem``. Each frame, in either
direction, is dropped with probability L, else sent D + U(-J, J) later (uniform jitter,
netem's default; frames leave in the order of their send times, so jitter reorders them
as netem does). Packet sockets with PACKET_VNET_HDR carry each frame's GSO and checksum
offload header across unchanged, so TCP segments of up to 64 kB go through whole.

``python -m tests.netem DEV_A DEV_B --delay 50ms --jitter 10ms --loss 1%`` (root, inside
the namespace that holds both devices); SIGTERM stops it and prints its counts.
"""

from __future__ import annotations

import argparse
import heapq
import json
import random
import select
import signal
import socket
import sys
import time

ETH_P_ALL = 0x0003
SOL_PACKET = 263
PACKET_VNET_HDR = 15
MAX_FRAME = 70000


def packet_socket(dev: str) -> socket.socket:
    """A non-blocking packet socket on ``dev`` for every protocol, with vnet headers."""
    s = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.htons(ETH_P_ALL))
    s.setsockopt(SOL_PACKET, PACKET_VNET_HDR, 1)
    s.bind((dev, 0))
    s.setblocking(False)
    return s


def seconds(text: str) -> float:
    """'50ms' -> 0.05, '1s' -> 1.0."""
    return float(text[:-2]) / 1e3 if text.endswith("ms") else float(text.rstrip("s"))


def fraction(text: str) -> float:
    """'1%' -> 0.01."""
    return float(text[:-1]) / 100 if text.endswith("%") else float(text)


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("dev_a")
    p.add_argument("dev_b")
    p.add_argument("--delay", type=seconds, default=0.0)
    p.add_argument("--jitter", type=seconds, default=0.0)
    p.add_argument("--loss", type=fraction, default=0.0)
    p.add_argument("--seed", type=int, default=None)
    args = p.parse_args()
    rng = random.Random(args.seed)
    a, b = packet_socket(args.dev_a), packet_socket(args.dev_b)
    peer = {a: b, b: a}
    pending: list[tuple[float, int, socket.socket, bytes]] = []
    counts = {"forwarded": 0, "dropped": 0, "send_errors": 0}
    running = True

    def stop(*_: object) -> None:
        nonlocal running
        running = False

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)
    n = 0
    while running:
        timeout = min(0.2, max(0.0, pending[0][0] - time.monotonic())) if pending else 0.2
        try:
            ready, _, _ = select.select([a, b], [], [], timeout)
        except InterruptedError:
            continue
        for s in ready:
            while True:
                try:
                    frame, addr = s.recvfrom(MAX_FRAME)
                except BlockingIOError:
                    break
                if addr[2] == socket.PACKET_OUTGOING:
                    continue
                if rng.random() < args.loss:
                    counts["dropped"] += 1
                    continue
                n += 1
                due = time.monotonic() + args.delay + rng.uniform(-args.jitter, args.jitter)
                heapq.heappush(pending, (due, n, peer[s], frame))
        now = time.monotonic()
        while pending and pending[0][0] <= now:
            _, _, out, frame = heapq.heappop(pending)
            try:
                out.send(frame)
                counts["forwarded"] += 1
            except OSError:  # the other side is down: the frame is lost, as on a cable
                counts["send_errors"] += 1
    print(f"netem {args.dev_a}<->{args.dev_b}: {json.dumps(counts)}", file=sys.stderr, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())

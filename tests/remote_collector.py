"""A collector for hosts the test process cannot reach (tests/integration/test_multihost.py): it
subscribes to key expressions under the root on its host's router and writes every
sample to stdout as msgpack ``[receive time, router time, key, payload]``.

Receive time: ``time.time()`` in the Zenoh callback. Router time: the sample's Zenoh
timestamp, which the first router on its path (the publisher's own router) sets when
the sample enters the network (None if it has none). All namespaces share the kernel's
clock, so times taken on different hosts compare directly. The collector declares
``<root>/alive/test/<name>`` once subscribed (the simulators wait for it) and stops on
SIGTERM. In a secured deployment (tests/integration/test_secured_network.py) it logs in
with ``--config F --identity NAME`` (the file's [zenoh.auth] / [zenoh.tls]) and declares
``--token`` instead (an identity may declare only its own tokens).

``python -m tests.remote_collector --connect tcp/127.0.0.1:7447 --name c1 KEYEXPR...``
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import queue
import sys
import time

import msgpack
import zenoh

from common.bus.transport import open_session, stop_on_signals
from common.deploy.config import ZenohConfig, load

Item = tuple[float, float | None, str, bytes]


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("keyexpr", nargs="+")
    p.add_argument("--connect", required=True)
    p.add_argument("--name", required=True)
    p.add_argument("--root", default="pf/v1")
    p.add_argument("--config", help="deployment file whose security tables apply")
    p.add_argument("--identity", help="Zenoh username under the file's [zenoh.auth]")
    p.add_argument("--token", help="liveliness token under the root (default alive/test/NAME)")
    args = p.parse_args()
    zc = ZenohConfig([args.connect], [], args.root)
    if args.config:
        zc = dataclasses.replace(load(args.config).zenoh, connect=[args.connect],
                                 identity=args.identity)
    stop = stop_on_signals()
    q: queue.Queue[Item] = queue.Queue()  # not SimpleQueue: see common.bus.transport.Inbox

    def on_sample(s: zenoh.Sample) -> None:  # tiny: stamp, copy, enqueue
        ts = s.timestamp
        q.put((time.time(), ts.get_time().timestamp() if ts is not None else None,
               str(s.key_expr), s.payload.to_bytes()))

    out = os.fdopen(os.dup(1), "wb")  # the samples; Zenoh's own log (RUST_LOG) goes to
    os.dup2(2, 1)                      # stdout: sent to stderr instead
    with open_session(zc) as session:
        subs = [session.declare_subscriber(f"{args.root}/{k}", on_sample) for k in args.keyexpr]
        token = session.liveliness().declare_token(
            f"{args.root}/{args.token or f'alive/test/{args.name}'}")
        while not stop.is_set():
            try:
                item: Item | None = q.get(timeout=0.1)
            except queue.Empty:
                continue
            while item is not None:
                out.write(msgpack.packb(list(item), use_bin_type=True))
                try:
                    item = q.get_nowait()
                except queue.Empty:
                    item = None
            out.flush()
        token.undeclare()
        for s in subs:
            s.undeclare()
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""A client that tries to publish forged samples (tests/integration/test_secured_network.py):
it logs in to a router with a deployment file's security tables, an identity and a
certificate of its own choice, and puts ``b"forged"`` on each key (plain session puts:
a client sends them to its router whether or not it knows of a subscriber). It prints
one JSON line: ``{"opened": bool, "put": n}`` (opened false: the router refused the
session).

``python -m tests.forger --config F --identity ID --cert C --key K --connect EP KEY...``
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys

import zenoh

from common.bus.transport import linger, open_session
from common.deploy.config import load

REPEAT = 5


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("key", nargs="+", help="keys under the root")
    p.add_argument("--config", required=True)
    p.add_argument("--identity", required=True)
    p.add_argument("--cert", required=True)
    p.add_argument("--key", dest="tls_key", required=True)
    p.add_argument("--connect", required=True)
    args = p.parse_args()
    z = load(args.config).zenoh
    assert z.tls is not None
    zc = dataclasses.replace(z, connect=[args.connect], identity=args.identity,
                             tls=dataclasses.replace(z.tls, cert=args.cert, key=args.tls_key))
    try:
        session = open_session(zc)
    except zenoh.ZError:
        print(json.dumps({"opened": False, "put": 0}), flush=True)
        return 0
    n = 0
    with session:
        for _ in range(REPEAT):
            for k in args.key:
                session.put(f"{z.root}/{k}", b"forged",
                            congestion_control=zenoh.CongestionControl.BLOCK)
                n += 1
        linger()
    print(json.dumps({"opened": True, "put": n}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())

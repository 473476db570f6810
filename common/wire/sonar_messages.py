"""Sonar message builders: core results (common.sonar) -> wire dicts of docs/protocol.md.

The services call these and nothing else to shape what they publish, so the wire form
of a sonar product is defined in one place (the radar ones: common.wire.radar_messages).
"""

from __future__ import annotations

from typing import Any

from common.sonar.bearing.tracker import Cycle
from common.wire import protocol


def btracks_message(array: str, c: Cycle, narrowband: bool) -> dict[str, Any]:
    """The btracks message of one cycle (docs/protocol.md)."""
    cols = zip(c.ids.tolist(), c.confirmed.tolist(), c.x.tolist(), [p.ravel().tolist() for p in c.P],
               c.quality.tolist(), c.ambiguous.tolist(), c.ml.tolist())
    tracks = []
    for tid, conf, x, P, q, amb, ml in cols:
        tr = {"id": tid, "status": "confirmed" if conf else "tentative", "x": x, "P": P,
              "quality": q, "ambiguous": amb}
        if ml >= 0:
            tr["ml"] = ml
        tracks.append(tr)
    msg: dict[str, Any] = {"v": protocol.VERSION, "t": c.t, "array": array, "tracks": tracks}
    if narrowband:
        msg["multiline"] = [
            {"id": m.id, "lines": m.lines, "brg": m.brg, "brg_rate": m.brg_rate}
            for m in c.multiline
        ]
    return msg

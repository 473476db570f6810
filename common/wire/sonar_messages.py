"""The sonar chain's messages (docs/protocol.md): builders from the seed 000, 002 and 003
cores' typed values (common.sonar) and parsers into them, so that the wire dicts exist
at the service boundary alone (the radar ones: common.wire.radar_messages). Parsers take
a message decoded by ``protocol.decode`` or as built.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from common.core.params import ParamError
from common.core.rejection import Rejected
from common.sonar.bearing.range_noise import TmaHint
from common.sonar.bearing.tracker import Cycle
from common.sonar.tma.bearings_only import Support
from common.sonar.tma.bounds import MINIMAL_BOUNDS, Bounds
from common.sonar.tma.constrained import CycleOutput
from common.sonar.tma.manager import (
    BOUNDS_FIELDS,
    BoundsParams,
    BTrack,
    BTracks,
    TmaReport,
    TrackHistory,
    make_bounds,
)
from common.wire import protocol

ACCEPTED = "accepted"  # the reason of an ack that accepts an operator input


def btracks_message(array: str, c: Cycle, narrowband: bool) -> dict[str, Any]:
    """The btracks message of one seed 000 cycle (docs/protocol.md)."""
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


def btracks_from(msg: dict[str, Any]) -> BTracks:
    """The seed 000 cycle of a btracks message as TMA reads it."""
    return BTracks(msg["t"], msg["array"], [
        BTrack(tr["id"], tr["status"] == "confirmed", np.asarray(tr["x"], dtype=float),
               np.asarray(tr["P"], dtype=float)) for tr in msg["tracks"]])


def history_message(array: str, t: float, track_id: int, found: tuple[str, dict[str, np.ndarray]]
                    ) -> dict[str, Any]:
    """The reply on sonar/history/<array>/<id>: status and register columns of one track
    (a tracker's ``history_of``) at tracker time t."""
    status, h = found
    return {"v": protocol.VERSION, "t": t, "array": array, "id": track_id, "status": status,
            "t_hist": h["t"], **{k: v for k, v in h.items() if k != "t"}}


def history_from(msg: dict[str, Any]) -> TrackHistory:
    """The seed 000 register of one track of a history reply."""
    rows = np.column_stack((msg["t_hist"], msg["brg"], msg["sbrg"], msg["own_x"], msg["own_y"]))
    return TrackHistory(msg["id"], msg["status"], rows)


def tma_message(r: TmaReport) -> dict[str, Any]:
    """The tma message of one TMA cycle (docs/protocol.md)."""
    return {"v": protocol.VERSION, "t": r.t, "array": r.array,
            "solutions": [_solution(tid, c) for tid, c in r.solutions],
            "births": [{"track": tid, "birth": b} for tid, b in r.births]}


def _solution(track: int, c: CycleOutput) -> dict[str, Any]:
    """One solution entry: state (m, m/s) and P at c.t, range/course/speed, CTMA status,
    and the flags of what it does not know (converged, ctma_exhausted, range_observable)."""
    b = c.bounds or MINIMAL_BOUNDS
    return {
        "track": track, "t": c.t, "x": c.x, "y": c.y, "vx": c.vx, "vy": c.vy,
        "P": np.asarray(c.P, float).reshape(-1).tolist(),
        "range": c.range, "course": c.course, "speed": c.speed,
        "constrained": c.constrained,
        "bounds": [b.r_min, b.r_max, b.k_min, b.k_max, b.v_min, b.v_max],
        "bounds_modified": c.bounds_modified, "phase": c.phase,
        "residual_factor": c.residual_factor, "legs": list(c.legs),
        "converged": c.converged, "ctma_exhausted": c.ctma_exhausted, "range_observable": c.range_observable,
    }


def tma_hints_from(msg: dict[str, Any]) -> list[tuple[int, TmaHint]]:
    """(track, TmaHint) of each solution of a tma message, as the bearing tracker uses them
    (common.sonar.bearing.range_noise, tma_prediction); a solution without the flags (an
    older publisher) is neither converged nor usable."""
    out = []
    for s in msg["solutions"]:
        conv = bool(s.get("converged", False))
        usable = conv and bool(s.get("range_observable", False))
        out.append((int(s["track"]), TmaHint(float(s["t"]), float(s["x"]), float(s["y"]), float(s["vx"]),
                                             float(s["vy"]), usable, np.asarray(s["P"], float).reshape(4, 4),
                                             conv)))
    return out


def bounds_from(msg: dict[str, Any]) -> tuple[Bounds, int | None]:
    """Checked seed 003 bounds of a tma_bounds message and the track they are for (None:
    every track). Bounds that break BoundsParams' rules are rejected as bad_bounds."""
    try:
        params = BoundsParams(*(msg[k] for k in BOUNDS_FIELDS))
    except ParamError as e:
        raise Rejected("bad_bounds", e.detail) from None
    return make_bounds(params), msg.get("track")


def support_from(msg: dict[str, Any]) -> tuple[int, Support]:
    """(track, seed 002 support value) of a tma_support message; a range needs obs_x,
    obs_y."""
    ox, oy = msg.get("obs_x"), msg.get("obs_y")
    if msg["kind"] == "range" and (ox is None or oy is None):
        raise Rejected("bad_support", "a range support needs obs_x and obs_y")
    xy = (0.0, 0.0) if ox is None or oy is None else (float(ox), float(oy))
    return msg["track"], Support(msg["kind"], float(msg["value"]), float(msg["sigma"]), float(msg["t"]), xy)


def bounds_message(t: float, b: BoundsParams, track: int | None = None, birth: float | None = None,
                   req: str | None = None) -> dict[str, Any]:
    """A tma_bounds message: the array's bounds, or one track's (of that birth); ``req``
    asks the tma service for an ack."""
    msg: dict[str, Any] = {"v": protocol.VERSION, "t": t, **{k: getattr(b, k) for k in BOUNDS_FIELDS}}
    return msg | _named(track, birth, req)


def support_message(track: int, s: Support, birth: float | None = None, req: str | None = None
                    ) -> dict[str, Any]:
    """A tma_support message of one seed 002 support value (a range with its position)."""
    msg: dict[str, Any] = {"v": protocol.VERSION, "t": s.t, "kind": s.kind, "value": s.value,
                           "sigma": s.sigma}
    if s.kind == "range":
        msg |= {"obs_x": s.obs_xy[0], "obs_y": s.obs_xy[1]}
    return msg | _named(track, birth, req)


def clear_message(t: float, track: int, what: str, birth: float | None = None,
                  req: str | None = None) -> dict[str, Any]:
    """A tma_clear message: forget a track's operator bounds, support values or both."""
    return {"v": protocol.VERSION, "t": t, "what": what} | _named(track, birth, req)


def _named(track: int | None, birth: float | None, req: str | None) -> dict[str, Any]:
    """The optional track, birth and request id of an operator input."""
    return {k: v for k, v in (("track", track), ("birth", birth), ("req", req)) if v is not None}


def ack_message(t: float, req: str, reason: str, track: int | None = None,
                birth: float | None = None) -> dict[str, Any]:
    """The tma service's answer to an operator input with a ``req``: ok when ``reason``
    is "accepted", else the rejection reason (docs/protocol.md)."""
    return {"v": protocol.VERSION, "t": t, "req": req, "ok": reason == ACCEPTED, "reason": reason,
            **_named(track, birth, None)}


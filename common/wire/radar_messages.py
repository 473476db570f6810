"""The radar chain's messages (docs/protocol.md): builders from the cores' typed arrays
and parsers into them, so that the cores see arrays only and the wire dicts exist at the
service boundary alone.

`etracks_of` is the global fusion's input parser: one vectorised pass over the decoded
msgpack map that accepts exactly what `protocol.decode("etracks", ...)` accepts (same
types, lengths, ranges, finiteness); on anything else it lets `protocol.decode` raise
its DecodeError naming the field, so the rejection reasons are the same. Why (its
cost against `protocol.decode`): docs/decisions/009-etracks-fast-parser.md.
"""

from __future__ import annotations

from itertools import chain
from typing import Any

import numpy as np

from common.core.rejection import Rejected
from common.core.track_table import STATUS_NAME, Status
from common.radar.elementary.tracker import ElementaryTracks
from common.radar.fusion.report import GlobalTracks
from common.radar.geometry.geodesy import LocalFrame
from common.radar.network.partition import Handed
from common.radar.plots.channel_fusion import Plots
from common.wire import protocol

STATUS_CODE = {name: int(code) for code, name in STATUS_NAME.items()}
MAX_INT = 2**62


def fused_message(base: str, t: float, fused: Plots) -> dict[str, Any]:
    """The `radar/fused/<base>` message of one scan (no az, saz at a range-Doppler base)."""
    if not fused.azimuth:
        return {"v": protocol.VERSION, "t": t, "base": base, "rb": fused.rb, "vb": fused.vb,
                "srb": fused.srb, "svb": fused.svb, "n_ch": fused.n_ch}
    return {"v": protocol.VERSION, "t": t, "base": base,
            "rb": fused.rb, "vb": fused.vb, "az": fused.az,
            "srb": fused.srb, "svb": fused.svb, "saz": fused.saz, "n_ch": fused.n_ch}


def plots_of(msg: dict[str, Any], azimuth: bool = True) -> Plots:
    """Plots of a `plots` or `fused` message, decoded or as built (n_ch only in the
    latter), from a base declared with `azimuth`. Raises Rejected `unexpected_azimuth`
    for az from a range-Doppler base, `missing_azimuth` for none from an azimuth base."""
    if ("az" in msg) != azimuth:
        raise Rejected("missing_azimuth" if azimuth else "unexpected_azimuth",
                       f"base '{msg.get('base')}' is declared azimuth = {str(azimuth).lower()}, "
                       f"its message {'has' if 'az' in msg else 'has no'} az")
    rb, vb, srb, svb = (np.asarray(msg[k], dtype=float) for k in ("rb", "vb", "srb", "svb"))
    az, saz = ((np.asarray(msg["az"], dtype=float), np.asarray(msg["saz"], dtype=float))
               if azimuth else (None, None))
    if "n_ch" in msg:
        return Plots(rb, vb, az, srb, svb, saz, np.asarray(msg["n_ch"], dtype=np.int64))
    return Plots(rb, vb, az, srb, svb, saz)


def etracks_message(base: str, tracks: ElementaryTracks) -> dict[str, Any]:
    """The `radar/etracks/<base>` message of one scan (every live track); `azimuth`:
    false for the 3-state tracks of a range-Doppler base (absent otherwise)."""
    rd = {} if tracks.x.shape[1] == protocol.ETRACK_SIZES[True] else {"azimuth": False}
    return {
        "v": protocol.VERSION, "t": tracks.t, "base": base, **rd,
        "tracks": [
            {"id": int(tracks.id[k]), "status": STATUS_NAME[Status(int(tracks.status[k]))],
             "x": tracks.x[k], "P": tracks.P[k].ravel(), "score": float(tracks.score[k]),
             "n_ch": int(tracks.n_ch[k]), "updated": bool(tracks.updated[k]),
             "ambiguous": bool(tracks.ambiguous[k])}
            for k in range(len(tracks))
        ],
    }


def etracks_from(msg: dict[str, Any]) -> tuple[str, ElementaryTracks]:
    """(base, elementary tracks) of an etracks message, decoded or as built: x (N, 5)
    and P (N, 5, 5), or x (N, 3) and P (N, 3, 3) from a range-Doppler base (the
    message's `azimuth`, absent: true, tells)."""
    tr = msg["tracks"]
    n = len(tr)
    k = protocol.ETRACK_SIZES[msg.get("azimuth", True)]
    return msg["base"], ElementaryTracks(
        t=float(msg["t"]), id=np.array([e["id"] for e in tr], dtype=np.int64),
        status=np.array([STATUS_CODE[e["status"]] for e in tr], dtype=np.int64),
        x=np.array([e["x"] for e in tr], dtype=float).reshape(n, k),
        P=np.array([e["P"] for e in tr], dtype=float).reshape(n, k, k),
        score=np.array([e["score"] for e in tr], dtype=float),
        n_ch=np.array([e["n_ch"] for e in tr], dtype=np.int64),
        updated=np.array([e["updated"] for e in tr], dtype=bool),
        ambiguous=np.array([e["ambiguous"] for e in tr], dtype=bool))


def _numbers(values: list[Any], integer: bool) -> bool:
    """Every value an int (integer) or an int / float (not bool: type() is exact)."""
    return set(map(type, values)) <= ({int} if integer else {int, float})


def _fast_etracks(obj: Any) -> tuple[str, ElementaryTracks] | None:
    """The typed report of an unpacked etracks map, or None when any field is not what
    protocol.ETRACKS allows (the caller then lets protocol.decode name it)."""
    if type(obj) is not dict or type(obj.get("v")) is not int or obj["v"] != protocol.VERSION:
        return None
    t: Any = obj.get("t")
    base: Any = obj.get("base")
    tracks: Any = obj.get("tracks")
    if (type(t) not in (int, float) or not np.isfinite(t) or t < 0 or type(base) is not str
            or not base or type(tracks) is not list):
        return None
    try:
        cols = {k: [e[k] for e in tracks] for k in protocol.ETRACK}
        status = [STATUS_CODE[s] for s in cols["status"]]
    except (TypeError, KeyError):  # an item that is not a map, a missing key, a bad status
        return None
    azimuth: Any = obj.get("azimuth", True)
    if type(azimuth) is not bool:
        return None
    n, k = len(tracks), protocol.ETRACK_SIZES[azimuth]
    if not (all(type(a) is list and len(a) == k for a in cols["x"])
            and all(type(a) is list and len(a) == k * k for a in cols["P"])
            and _numbers(cols["id"], True) and _numbers(cols["n_ch"], True)
            and _numbers(cols["score"], False) and _numbers(list(chain.from_iterable(cols["x"])), False)
            and _numbers(list(chain.from_iterable(cols["P"])), False)
            and set(map(type, cols["updated"] + cols["ambiguous"])) <= {bool}):
        return None
    if any(not 0 <= i <= MAX_INT for i in cols["id"] + cols["n_ch"]):
        return None
    x = np.array(cols["x"], dtype=float).reshape(n, k)
    P = np.array(cols["P"], dtype=float).reshape(n, k, k)
    score = np.array(cols["score"], dtype=float)
    if not (np.isfinite(x).all() and np.isfinite(P).all() and np.isfinite(score).all()):
        return None
    return base, ElementaryTracks(
        t=float(t), id=np.array(cols["id"], dtype=np.int64), status=np.array(status, dtype=np.int64),
        x=x, P=P, score=score, n_ch=np.array(cols["n_ch"], dtype=np.int64),
        updated=np.array(cols["updated"], dtype=bool), ambiguous=np.array(cols["ambiguous"], dtype=bool))


def etracks_of(payload: bytes) -> tuple[str, ElementaryTracks]:
    """Parse and validate a `radar/etracks/<base>` payload into (base, elementary
    tracks); raises protocol.DecodeError (naming the field) as protocol.decode does."""
    fast = _fast_etracks(protocol.unpack(payload))
    return fast if fast is not None else etracks_from(protocol.decode("etracks", payload))


def gtracks_message(g: GlobalTracks, origin: LocalFrame | None = None) -> dict[str, Any]:
    """The `radar/gtracks` message of one fusion cycle (every live global track); the
    columns go to Python lists in one `tolist` each (per-track conversion cost 1.6 ms a
    dense.toml cycle). With the deployment's ``origin`` (a geodetic deployment) each
    track also carries lat, lon, alt: the WGS-84 position of its local x, y, z."""
    n = len(g)
    bases = list(g.bases)
    member, has = g.member.tolist(), g.has.tolist()
    msg: dict[str, Any] = {"v": protocol.VERSION, "t": g.t, "tracks": [
        {"id": i, "status": STATUS_NAME[s], "x": x, "P": p, "score": sc,
         "etracks": [[bases[b], m[b]] for b, on in enumerate(h) if on], "ambiguous": a}
        for i, s, x, p, sc, m, h, a in zip(g.id.tolist(), g.status.tolist(), g.x.tolist(),
                                            g.P.reshape(n, 36).tolist(), g.score.tolist(),
                                            member, has, g.ambiguous.tolist())]}
    if origin is not None and n:
        lat, lon, alt = (c.tolist() for c in origin.to_geodetic(g.x[:, [0, 2, 4]]))
        for track, la, lo, h in zip(msg["tracks"], lat, lon, alt):
            track.update(lat=la, lon=lo, alt=h)
    return msg


def confirmed_tracks(msg: dict[str, Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The confirmed tracks of a decoded `radar/gtracks` message, as scored against truth:
    ids (m,), x (m, 6) [x vx y vy z vz], P (m, 6, 6)."""
    conf = [k for k in msg["tracks"] if k["status"] == "confirmed"]
    return (np.array([k["id"] for k in conf], dtype=np.int64),
            np.array([k["x"] for k in conf], dtype=float).reshape(-1, 6),
            np.array([k["P"] for k in conf], dtype=float).reshape(-1, 6, 6))


def handover_message(sender: str, to: str, h: Handed) -> dict[str, Any]:
    """The `radar/handover/<to>` message of a track that partition `sender` hands over."""
    return {"v": protocol.VERSION, "t": h.t, "from": sender, "to": to, "track": {
        "id": h.number, "status": STATUS_NAME[Status(h.status)], "x": h.x.tolist(),
        "P": h.P.reshape(36).tolist(), "t_update": h.t_update, "born": h.born, "hits": h.hits,
        "etracks": [list(m) for m in h.members]}}


def handed_of(payload: bytes) -> tuple[str, str, Handed]:
    """Sender, receiver and track of a `radar/handover/<to>` payload (DecodeError)."""
    msg = protocol.decode("handover", payload)
    k = msg["track"]
    return msg["from"], msg["to"], Handed(
        k["id"], STATUS_CODE[k["status"]], msg["t"], k["x"], k["P"].reshape(6, 6),
        k["t_update"], k["born"], k["hits"], tuple(k["etracks"]))


def handover_ack_message(sender: str, to: str, t: float, number: int) -> dict[str, Any]:
    """The `radar/handover_ack/<to>` message: partition `sender` holds track `number`."""
    return {"v": protocol.VERSION, "t": t, "from": sender, "to": to, "id": number}


def claimed_members(payload: bytes) -> list[tuple[str, int]]:
    """The (base, elementary id) members of every track of a `radar/gtracks` payload."""
    return [m for k in protocol.decode("gtracks", payload)["tracks"] for m in k["etracks"]]

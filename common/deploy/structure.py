"""The structure tables of a deployment file, declared once: ``[zenoh]``,
``[radar.origin]``, ``[[radar.base]]`` and ``[[sonar.array]]`` (``[[site]]``,
``[zenoh.auth]`` and ``[zenoh.tls]`` are the dataclasses of common.deploy.config).

The loader (common.deploy.config) takes the keys it accepts from here and the reference
page (common.deploy.sections, docs/configuration.md) lists them from here, so the two
cannot disagree (tests/deploy/test_structure.py)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Key:
    """One key of a structure table: its TOML type, default ("(required)" when it must be
    given), unit, admissible values and meaning, as docs/configuration.md shows them."""

    name: str
    type: str
    default: str
    unit: str = ""
    range: str = ""
    meaning: str = ""


@dataclass(frozen=True)
class Table:
    """A structure table: its heading in docs/configuration.md, one line on what it is,
    its keys, and the rules between them."""

    heading: str
    summary: str
    keys: tuple[Key, ...]
    rules: tuple[str, ...] = ()

    def names(self) -> frozenset[str]:
        """The keys the loader accepts in this table."""
        return frozenset(k.name for k in self.keys)


CHUNK = "a Zenoh key chunk: no / * $ ? #, no whitespace, not starting with @"
ENDPOINT = "tcp \\| udp \\| tls \\| quic \\| ws \\| unixsock-stream / address"

ZENOH = Table("[zenoh]", "Where every process of the deployment connects and listens, and the key root.", (
    Key("connect", "list[str]", "['tcp/127.0.0.1:7447']", "", ENDPOINT,
        "endpoints a process connects to (`pfusion run --with-router` listens on the first); "
        "`--connect` on the command line overrides it"),
    Key("listen", "list[str]", "[]", "", ENDPOINT, "endpoints a process listens on (routers)"),
    Key("root", "str", "'pf/v1'", "", "", "prefix of every data key (docs/protocol.md)"),
    Key("auth", "table", "(none)", "", "", "[zenoh.auth] below: user/password authentication"),
    Key("tls", "table", "(none)", "", "", "[zenoh.tls] below: TLS on every link"),
    Key("identity", "str", "(none)", "", "",
        "not a file key: a process's Zenoh username is `--identity` or derived from the "
        "deployment (`pfusion acl`); a value given here is replaced at start-up"),
))

ORIGIN = Table("[radar.origin]", "The WGS-84 point of the local East-North-Up frame (absent: a flat frame).", (
    Key("lat", "float", "(required)", "deg", "[-90, 90]", "geodetic latitude of the frame's origin"),
    Key("lon", "float", "(required)", "deg", "[-180, 180]", "longitude of the frame's origin"),
    Key("alt", "float", "(required)", "m", "finite", "ellipsoidal height of the origin (not above mean sea level)"),
), ("the table has exactly lat, lon and alt",))

BASE = Table("[[radar.base]]", "One bistatic base: a receiver and one transmitter of opportunity (001).", (
    Key("id", "str", "(required)", "", CHUNK, "the base's id (keys `radar/plots/<id>/*`, `--base`)"),
    Key("tx", "list[float]", "(required: tx or tx_geo)", "m", "3 finite values",
        "transmitter position [x, y, z] in the local frame (x East, y North, z up)"),
    Key("rx", "list[float]", "(required: rx or rx_geo)", "m", "3 finite values", "receiver position [x, y, z]"),
    Key("tx_geo", "list[float]", "(none)", "deg, deg, m", "\\|lat\\| <= 90, \\|lon\\| <= 180",
        "transmitter as [lat, lon, alt] (WGS-84, ellipsoidal height); needs [radar.origin]"),
    Key("rx_geo", "list[float]", "(none)", "deg, deg, m", "\\|lat\\| <= 90, \\|lon\\| <= 180",
        "receiver as [lat, lon, alt]; needs [radar.origin]"),
    Key("channels", "list[str]", "(required)", "", f"non-empty, unique, each {CHUNK}",
        "the base's channels (keys `radar/plots/<id>/<channel>`)"),
    Key("p", "int", "1", "count", "[0, inf)",
        "module 34: with n > 2 channels a fused plot is kept when seen on >= n - p of them"),
    Key("azimuth", "bool", "True", "", "",
        "the receiver measures theta (001 [3]); false for a range-Doppler base (plots [r_b, v_b]; "
        "global fusion refuses such a deployment)"),
), ("exactly one of tx / tx_geo and one of rx / rx_geo", "tx and rx differ", "ids unique over the bases"))

ARRAY = Table("[[sonar.array]]", "One hydrophone array of the sonar chain (000).", (
    Key("id", "str", "(required)", "", CHUNK, "the array's id (keys `sonar/detections/<id>`, `--array`)"),
    Key("kind", '"cylindrical" \\| "linear"', "'cylindrical'", "", "",
        "cylindrical: bearing sigma sigma0; linear: 000 claim 6's law sigma0 / (\\|sin(theta - theta_0)\\| sqrt(a))"),
    Key("sigma0", "float", "(required)", "rad", "(0, pi)", "bearing standard deviation of a detection"),
), ("ids unique over the arrays",))

TABLES: dict[str, Table] = {"zenoh": ZENOH, "radar.origin": ORIGIN, "radar.base": BASE, "sonar.array": ARRAY}

"""The router's audit: access-control denials and failed logins as rate-limited WARNING
lines naming identity, key and cause, and counters (docs/security.md, "Audit").

Zenoh 1.10.2 has no hook for either: it writes a denial as a TRACE event of
``zenoh::net::routing::interceptor::access_control`` ("<zid> on <subject> is
unauthorized to Put (ingress) on <key>"), a session that matches no subject as one INFO
event there, a failed password check as a DEBUG event of
``zenoh_transport::unicast::establishment::accept`` ("UsrPwd extension - Recv OpenSyn.
Invalid password.", without the user), a refused client certificate as a WARN event of
``zenoh_link_tls::unicast`` (without the address). The router raises those targets for
itself (AUDIT_TARGETS) and feeds its own log lines to :class:`Audit`, which joins each
refusal to what the same accepting thread logged just before: the remote address and
ZID (the InitSyn trace), the user (decoded from the usrpwd extension of the OpenSyn
trace) and the certificate's common name (the TLS accept).

Zenoh evaluates a key expression that a session declares (a publisher, subscriber,
queryable, token) once for every kind of message (BLOCK of them, in one go on one
thread), and writes a denial line for each kind the session may not use, whether or not
it ever tries; a message on an undeclared key is evaluated, and written, one by one.
So consecutive denials of one thread on one session, key and direction are grouped:
one kind alone is a refused message (``denied``); a block that denies every kind on
ingress for a key on and below which the identity has no right at all (``may_use``: a
service declares the prefix of its wildcard keys too) is a session using a key it has
no right to (``denied``); any other block is the routine map of what a session may not
do with a key it declared (``key_denied``, counted, logged at DEBUG only). A
declaration refused on a key where the identity has some other right is therefore
only a ``key_denied``.

Pure: lines and the time in, events and counters out (common.bus.log_tap does the I/O).
"""

from __future__ import annotations

import re
from collections import Counter, OrderedDict
from collections.abc import Callable
from dataclasses import dataclass

ACL = "zenoh::net::routing::interceptor::access_control"
ACCEPT = "zenoh_transport::unicast::establishment::accept"
TLS = "zenoh_link_tls::unicast"
AUDIT_TARGETS = [(ACL, 5), (ACCEPT, 5), (TLS, 4)]  # (target, level index in rust_log.LEVELS)
PERIOD_S = 10.0  # one line per (kind, identity, key or cause) per period
MAX_LINES = 50   # lines per period over all of them; the rest are counted, not written
REMEMBERED = 1024  # connections (address, ZID, user, common name) kept for the joins
USRPWD_EXT = 2  # the user/password sub-extension of the auth extension
BLOCK = 9  # kinds of message Zenoh evaluates at once for a declared key expression
GROUP_S = 0.2  # a group of denials that no line continued for this long is complete
QUIET = ("key_denied",)  # kinds logged at DEBUG only: routine permission blocks

_ANSI = re.compile(r"\x1b\[[0-9;]*m")
_LINE = re.compile(r"^\S+\s+(TRACE|DEBUG|INFO|WARN|ERROR)\s+(?:(\S+)\s+)?ThreadId\(\d+\)\s"
                   r"(?:.*?\s)?(zenoh\w*(?:::\w+)*): (.*)$")
_DENIED = re.compile(r"^(\w+) on (.+?) is unauthorized to (.+?) \((ingress|egress)\) on (\S+)$")
_NO_SUBJECT = re.compile(r"^(\w+) did not match any configured ACL subject")
_ESTABLISH = re.compile(r"^Establishment Accept (InitSyn|OpenSyn): \S+ => (\S+?)\. Received")
_ZID = re.compile(r"\bzid: (\w+)")
_AUTH = re.compile(r"ext_auth: Some\(ZExtZBuf \{[^{}]*Value: ZBuf \{ slices: \[(.*?)\] \}")
_REFUSED = re.compile(r"^UsrPwd extension - Recv (?:InitSyn|OpenSyn)\. (Invalid password|"
                      r"Invalid user|Expected extension)\.")
_TLS_ACCEPTED = re.compile(r"^Accepted TLS connection on \S+: (\S+?)\. Common Name: (.*?)\.?$")
_TLS_REFUSED = re.compile(r"^(invalid peer certificate: \w+)")  # not "tls handshake eof": a port probe
_FIELD = re.compile(r"(Username|CertCommonName)\(([^)]*)\)")
CAUSES = {"Invalid password": "wrong password", "Invalid user": "unknown user",
          "Expected extension": "no user/password"}


@dataclass(frozen=True)
class Event:
    """One refusal: ``kind`` (denied, key_denied, login_failed, tls_refused, no_subject), who
    (``user@common-name``, '?' for a part not known), what, why, and the remote address
    when known; ``line`` is the audit line."""

    kind: str
    identity: str
    key: str
    cause: str
    source: str = "?"

    @property
    def line(self) -> str:
        return f"audit {self.kind}: identity {self.identity} from {self.source} key {self.key} ({self.cause})"


def split(line: str) -> tuple[str, str, str, str] | None:
    """(level, thread, target, message) of one of Zenoh's log lines, else None."""
    m = _LINE.match(_ANSI.sub("", line.rstrip("\n")))
    return None if m is None else (m.group(1), m.group(2) or "", m.group(3), m.group(4))


def _varint(b: list[int], i: int) -> tuple[int, int]:
    n = shift = 0
    while i < len(b):
        n |= (b[i] & 0x7F) << shift
        i += 1
        if not b[i - 1] & 0x80:
            break
        shift += 7
    return n, i


def auth_user(message: str) -> str | None:
    """The user an OpenSyn trace carries in its usrpwd extension (length-prefixed user,
    then the HMAC of the password: never the password), else None."""
    m = _AUTH.search(message)
    if m is None:
        return None
    b = [int(x, 16) for x in re.findall(r"[0-9a-fA-F]{2}", m.group(1))]
    i = 0
    while i < len(b):
        header = b[i]
        i += 1
        body: list[int] = []
        if header & 0x60 == 0x40:  # a ZBuf: length, bytes
            n, i = _varint(b, i)
            body, i = b[i:i + n], i + n
        elif header & 0x60 == 0x20:  # a Z64
            _, i = _varint(b, i)
        if header & 0x0F == USRPWD_EXT and body:
            n, j = _varint(body, 0)
            return bytes(body[j:j + n]).decode("utf-8", "replace")
        if not header & 0x80:
            break
    return None


def subject_name(subject: str) -> str:
    """``user@common-name`` of an ACL subject ("Interface(lo)+CertCommonName(h)+
    Username(u)+..."); '?' for a part that is not there."""
    fields = dict(_FIELD.findall(subject))
    return f"{fields.get('Username', '?')}@{fields.get('CertCommonName', '?')}"


@dataclass
class _Group:
    """Consecutive denials of one accepting thread on one session, key and direction."""

    zid: str
    identity: str
    key: str
    flow: str
    actions: list[str]
    since: float


@dataclass
class _Conn:
    remote: str = "?"
    zid: str = ""
    user: str = "?"
    cn: str = "?"

    @property
    def who(self) -> str:
        return f"{self.user}@{self.cn}"


class Audit:
    """Zenoh log lines in (:meth:`feed`), audit events and counters out; :meth:`lines`
    rate-limits them (PERIOD_S per kind, identity, key and cause; MAX_LINES per period)."""

    def __init__(self, period_s: float = PERIOD_S, max_lines: int = MAX_LINES,
                 may_use: Callable[[str, str], bool] | None = None) -> None:
        """``may_use(user, key)``: whether the access control gives ``user`` some right on
        ``key`` or below it (a declared prefix of the keys it uses is no attempt)."""
        self.may_use = may_use
        self.counters: Counter[str] = Counter()
        self.period_s, self.max_lines = period_s, max_lines
        self._conns: OrderedDict[str, _Conn] = OrderedDict()  # by remote address
        self._thread: dict[str, _Conn] = {}  # the connection each accepting thread works on
        self._groups: dict[str, _Group] = {}  # denials being grouped, by routing thread
        self._last: dict[tuple[str, str, str, str], tuple[float, int]] = {}
        self._window = (0.0, 0)  # start of the current period, lines written in it
        self.suppressed = 0

    def _conn(self, remote: str) -> _Conn:
        c = self._conns.pop(remote, None) or _Conn(remote)
        self._conns[remote] = c
        while len(self._conns) > REMEMBERED:
            self._conns.popitem(last=False)
        return c

    def feed(self, line: str, now: float = 0.0) -> list[Event]:
        """One log line at ``now`` (s, any clock): the refusals it completes (counted)."""
        parts = split(line)
        if parts is None:
            return self.flush(now)
        _, thread, target, msg = parts
        events = self.flush(now)
        if target == ACL:
            events += self._acl(thread, msg, now)
        elif target == ACCEPT:
            events += [e for e in [self._accept(thread, msg)] if e is not None]
        elif target == TLS:
            events += [e for e in [self._tls(thread, msg)] if e is not None]
        return self._count(events)

    def flush(self, now: float) -> list[Event]:
        """The refusals of permission groups that no line continued for GROUP_S."""
        done = [t for t, g in self._groups.items() if now - g.since >= GROUP_S]
        return self._count([self._close(self._groups.pop(t)) for t in done])

    def _count(self, events: list[Event]) -> list[Event]:
        for e in events:
            self.counters[e.kind] += 1
        return events

    def _acl(self, thread: str, msg: str, now: float) -> list[Event]:
        if m := _DENIED.match(msg):
            zid, subject, action, flow, key = m.groups()
            g = self._groups.get(thread)
            if g is not None and (g.zid, g.key, g.flow) == (zid, key, flow) \
                    and action not in g.actions:
                g.actions.append(action)
                return [self._close(self._groups.pop(thread))] if len(g.actions) == BLOCK else []
            out = [self._close(self._groups.pop(thread))] if g is not None else []
            self._groups[thread] = _Group(zid, subject_name(subject), key, flow, [action], now)
            return out
        if m := _NO_SUBJECT.match(msg):
            zid = m.group(1)
            conn = next((c for c in reversed(self._conns.values()) if c.zid == zid), _Conn())
            return [Event("no_subject", conn.who, "*", f"zid {zid} matches no ACL subject: "
                                                       "everything it sends is denied", conn.remote)]
        return []

    def _close(self, g: _Group) -> Event:
        """A single refused message, or a permission block (Zenoh evaluates every kind of
        message at once for a key expression a session declares): a block that denies
        every kind on ingress means the session used a key it has no right to at all."""
        if len(g.actions) == 1 and not g.actions[0].startswith("Declare/Undeclare"):
            return Event("denied", g.identity, g.key, f"{g.actions[0]} {g.flow}")
        user = g.identity.split("@", 1)[0]
        if len(g.actions) == BLOCK and g.flow == "ingress" and not (
                self.may_use is not None and self.may_use(user, g.key)):
            return Event("denied", g.identity, g.key, "no right at all on this key, ingress")
        return Event("key_denied", g.identity, g.key, f"may not: {', '.join(g.actions)} ({g.flow})")

    def _accept(self, thread: str, msg: str) -> Event | None:
        if m := _ESTABLISH.match(msg):
            conn = self._thread[thread] = self._conn(m.group(2).split("/", 1)[-1])
            if m.group(1) == "InitSyn" and (z := _ZID.search(msg)):
                conn.zid = z.group(1)
            elif user := auth_user(msg):
                conn.user = user
            return None
        if m := _REFUSED.match(msg):
            conn = self._thread.get(thread, _Conn())
            return Event("login_failed", conn.who, "-", CAUSES[m.group(1)], conn.remote)
        return None

    def _tls(self, thread: str, msg: str) -> Event | None:
        if m := _TLS_ACCEPTED.match(msg):
            self._thread[thread] = conn = self._conn(m.group(1))
            conn.cn = m.group(2)
            return None
        if m := _TLS_REFUSED.match(msg):
            return Event("tls_refused", "?", "-", m.group(1))
        return None

    def lines(self, event: Event, now: float) -> list[str]:
        """The audit lines to write for ``event`` at ``now`` (s, any clock): the first
        of its (kind, identity, key, cause) in a period, with how many were not written since."""
        if now - self._window[0] >= self.period_s:
            out = [f"audit: {self.suppressed} more line(s) not written in the last "
                   f"{self.period_s:.0f} s"] if self.suppressed else []
            self._window, self.suppressed = (now, 0), 0
            if len(self._last) > 4 * REMEMBERED:
                self._last = {k: v for k, v in self._last.items() if now - v[0] < self.period_s}
        else:
            out = []
        k = (event.kind, event.identity, event.key, event.cause)
        last, since = self._last.get(k, (-self.period_s, 0))
        if now - last < self.period_s:
            self._last[k] = (last, since + 1)
            return out
        if self._window[1] >= self.max_lines:
            self.suppressed += 1
            return out
        self._last[k] = (now, 0)
        self._window = (self._window[0], self._window[1] + 1)
        more = f"; {since} more since the last line" if since else ""
        return [*out, event.line + more]

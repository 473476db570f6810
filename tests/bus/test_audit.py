"""common.bus.audit on lines Zenoh 1.10.2 wrote (a router's log under RUST_LOG=trace,
shortened where marked ...): denials, a session that matches no subject and failed
logins become events with identity, key and cause; the user is decoded from the
OpenSyn's usrpwd extension; lines are rate-limited per (kind, identity, key, cause). Denials of one key expression's
permission block (every kind of message at once, when a session declares it) are
told apart from refused messages."""

from __future__ import annotations

from common.bus.audit import GROUP_S, Audit, Event, auth_user, split

E = "\x1b[2m"  # Zenoh colours its log unless NO_COLOR is set
TLS_OK = ("2026-11-28T03:19:09.625690Z DEBUG acc-0 ThreadId(05) zenoh_link_tls::unicast: "
          "Accepted TLS connection on 127.0.0.1:43481: 127.0.0.1:57982. Common Name: host.")
INIT = ("2026-11-28T03:19:09.626030Z TRACE acc-0 ThreadId(05) zenoh_transport::unicast::"
        "establishment::accept: Establishment Accept InitSyn: tls/127.0.0.1:43481 => "
        "tls/127.0.0.1:57982. Received: TransportMessage { body: InitSyn(InitSyn { version: 9, "
        "whatami: Client, zid: 1c1732dcba5e0acf0af40407974c742a, resolution: Resolution(10), ...")
OPEN = ("2026-11-28T03:19:09.626785Z TRACE acc-0 ThreadId(05) zenoh_transport::unicast::"
        "establishment::accept: Establishment Accept OpenSyn: tls/127.0.0.1:43481 => "
        "tls/127.0.0.1:57982. Received: TransportMessage { body: OpenSyn(OpenSyn { lease: 10s, "
        "... ext_auth: Some(ZExtZBuf { Id: 3, Mandatory: false, Encoding: \"ZBuf\", Value: ZBuf "
        "{ slices: [[42, 24, 02, 75, 31, 20, 3a, ff, 23, 64, 5b, 07, bc, 35, 7e, 9a, 65, 08, cc, "
        "9c, 2b, cf, b1, be, a5, 6d, e5, 63, 25, 8e, 00, 10, e9, 3e, 6d, e2, fa, d5]] } }), "
        "ext_mlink: None, ext_lowlatency: None, ext_compression: None, ext_remote_bound: None }) }")
BAD_PASSWORD = ("2026-11-28T03:19:09.626897Z DEBUG acc-0 ThreadId(05) zenoh_transport::unicast::"
                "establishment::accept: UsrPwd extension - Recv OpenSyn. Invalid password. at "
                "/root/.cargo/git/checkouts/zenoh-9c599d5ef3e0480e/cc83980/io/zenoh-transport/src/"
                "unicast/establishment/ext/auth/usrpwd.rs:424.")
NO_AUTH = ("2026-11-28T03:19:19.517846Z DEBUG acc-1 ThreadId(06) zenoh_transport::unicast::"
           "establishment::accept: UsrPwd extension - Recv InitSyn. Expected extension. at "
           "/root/.cargo/git/checkouts/zenoh-9c599d5ef3e0480e/cc83980/io/zenoh-transport/src/"
           "unicast/establishment/ext/auth/usrpwd.rs:380.")
DENIED = (f"{E}2026-11-28T03:19:22.843316Z\x1b[0m \x1b[35mTRACE\x1b[0m  rx-1 ThreadId(09) "
          f"{E}demux{{zid=486c3fb86f7aa9b5fa12fa6dac10eee4 src=south:0:client/b817917d:1}}: "
          f"{E}zenoh::net::routing::interceptor::access_control\x1b[0m: b817917d3651cb7d0955b7beeb6d18ae"
          " on Interface(lo)+CertCommonName(host)+Username(site-rx1)+Transport(Tls)+"
          "b817917d3651cb7d0955b7beeb6d18ae is unauthorized to Put (ingress) on pf/v1/radar/gtracks")
ALLOWED = DENIED.replace("is unauthorized", "is authorized")
NO_SUBJECT = ("2026-11-28T03:19:23.667697Z  INFO acc-0 ThreadId(05) rt{zid=486c3fb8}: zenoh::net"
              "::routing::interceptor::access_control: 1c1732dcba5e0acf0af40407974c742a did not "
              "match any configured ACL subject. Default permission `Deny` will be applied on all "
              "messages")
BAD_CERT = ("2026-11-28T03:19:16.196558Z  WARN acc-1 ThreadId(06) zenoh_link_tls::unicast: invalid "
            "peer certificate: UnknownIssuer. Hint: increase the system open file limit.")


def test_lines_split_into_level_thread_target_message() -> None:
    assert split(DENIED)[:3] == ("TRACE", "rx-1", "zenoh::net::routing::interceptor::access_control")
    assert split(NO_SUBJECT)[:3] == ("INFO", "acc-0", "zenoh::net::routing::interceptor::access_control")
    assert split("2026-11-28 03:22:29,194 INFO router: router listening") is None


def test_the_user_is_read_from_the_usrpwd_extension() -> None:
    assert auth_user(OPEN) == "u1"
    assert auth_user(INIT) is None


def one(events: list[Event]) -> Event:
    assert len(events) == 1, events
    return events[0]


def test_events_name_identity_key_and_cause() -> None:
    a = Audit()
    assert [a.feed(line) for line in (TLS_OK, INIT, OPEN)] == [[], [], []]
    e = one(a.feed(BAD_PASSWORD))
    assert (e.kind, e.identity, e.source, e.cause) == (
        "login_failed", "u1@host", "127.0.0.1:57982", "wrong password")
    e = one(a.feed(NO_SUBJECT))
    assert (e.kind, e.identity, e.source) == ("no_subject", "u1@host", "127.0.0.1:57982")
    assert a.feed(DENIED, 1.0) == []  # held: the first of a permission block?
    assert a.feed(ALLOWED, 1.0) == []
    e = one(a.flush(1.5))  # alone for more than GROUP_S: one refused message
    assert (e.kind, e.identity, e.key, e.cause) == (
        "denied", "site-rx1@host", "pf/v1/radar/gtracks", "Put ingress")
    e = one(a.feed(NO_AUTH, 2.0))  # another thread: nothing known of its connection
    assert (e.identity, e.cause) == ("?@?", "no user/password")
    e = one(a.feed(BAD_CERT, 2.0))
    assert (e.kind, e.cause) == ("tls_refused", "invalid peer certificate: UnknownIssuer")
    assert dict(a.counters) == {"login_failed": 2, "no_subject": 1, "denied": 1, "tls_refused": 1}


KINDS = ["Query", "Reply", "Put", "Delete", "Declare/Undeclare Subscriber",
         "Declare/Undeclare Queryable", "Declare/Undeclare Liveliness Token", "Liveliness Query",
         "Declare Liveliness Subscriber"]


def block(kinds: list[str], flow: str = "ingress", key: str = "pf/v1/radar/gtracks") -> list[str]:
    """The denial lines of one key expression's permission block (Zenoh's order)."""
    return [DENIED.replace("Put (ingress)", f"{k} ({flow})").replace("pf/v1/radar/gtracks", key)
            for k in kinds]


def test_repeated_messages_are_each_a_denial_permission_blocks_are_not() -> None:
    a = Audit()
    events = [e for line in [DENIED] * 3 for e in a.feed(line)] + a.flush(GROUP_S)
    assert [e.kind for e in events] == ["denied"] * 3
    # a key the session declared, on which it may put and subscribe but do nothing else
    routine = [k for k in KINDS if k not in ("Put", "Declare/Undeclare Subscriber")]
    events = [e for line in block(routine) for e in a.feed(line, 1.0)] + a.flush(2.0)
    e = one(events)
    assert (e.kind, e.cause) == ("key_denied", f"may not: {', '.join(routine)} (ingress)")
    # a key it may do nothing with (a subscriber on another site's plots, a forged token)
    events = [e for line in block(KINDS, key="pf/v1/alive/tma/a2") for e in a.feed(line, 3.0)]
    e = one(events)  # complete at the ninth kind
    assert (e.kind, e.key, e.cause) == ("denied", "pf/v1/alive/tma/a2",
                                        "no right at all on this key, ingress")
    events = [e for line in block(KINDS, "egress") for e in a.feed(line, 4.0)]
    assert one(events).kind == "key_denied"  # what the router does not send it: routine
    assert a.counters["denied"] == 4 and a.counters["key_denied"] == 2


def test_lines_are_rate_limited() -> None:
    a = Audit(period_s=10.0, max_lines=3)
    e = one(a.feed(DENIED) + a.flush(GROUP_S))
    assert a.lines(e, 0.0) == [e.line]
    assert [a.lines(e, t) for t in (1.0, 2.0, 9.9)] == [[], [], []]
    assert a.lines(e, 10.0) == [e.line + "; 3 more since the last line"]
    other = [e for i in range(4)
             for e in a.feed(DENIED.replace("radar/gtracks", f"radar/plots/b9/c{i}"))]
    other += a.flush(GROUP_S)
    written = [line for o in other for line in a.lines(o, 11.0)]
    assert len(written) == 2  # with the first of the period, 3 lines in it
    assert a.lines(e, 21.0)[0].startswith("audit: 2 more line(s) not written")
    assert a.counters["denied"] == 5

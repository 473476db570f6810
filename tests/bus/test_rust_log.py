"""common.bus.rust_log: the RUST_LOG a process gives Zenoh never enables the target
that logs the configuration (passwords included) below info, whatever was asked, and
keeps every other level asked for. A real Zenoh session opened under RUST_LOG=trace
logs the password without the cap and not with it (so the check can fail)."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from common.bus.rust_log import LEVELS, enabled, parse, sanitise

SECRET = "zenoh::api::session"


@pytest.mark.parametrize("asked", [
    "trace", "debug", "zenoh=trace", "zenoh::api::session=trace", "zenoh::api::sess=trace",
    "zenoh::api::session::x=trace,zenoh::api::session=debug", "info,zenoh::api=trace",
    "[{zid}]=trace", "zenoh[span]=trace,trace", "warn,zenoh::api::session", "TRACE",
])
def test_the_config_target_is_never_above_info(asked: str) -> None:
    spec = parse(sanitise(asked))
    assert not enabled(spec, SECRET, "debug"), (asked, sanitise(asked))


def test_other_levels_are_kept() -> None:
    spec = parse(sanitise("debug,zenoh_transport=trace,zenoh::net=warn"))
    assert enabled(spec, "zenoh_transport::unicast::manager", "trace")
    assert enabled(spec, "zenoh_link_tcp", "debug") and not enabled(spec, "zenoh_link_tcp", "trace")
    assert enabled(spec, "zenoh::net::runtime", "warn") and not enabled(spec, "zenoh::net::runtime", "info")
    assert enabled(spec, SECRET, "info")
    assert sanitise(None) == sanitise("") == ""
    assert not enabled(parse(sanitise("off")), SECRET, "info")  # off stays off
    assert not enabled(parse(sanitise("warn")), SECRET, "info")  # never raised by the cap


def test_extra_targets_are_added_but_never_a_secret_one() -> None:
    spec = parse(sanitise("warn", [("zenoh::net::routing::interceptor::access_control", 5),
                                   (SECRET, 5)]))
    assert enabled(spec, "zenoh::net::routing::interceptor::access_control::x", "trace")
    assert not enabled(spec, "zenoh::net::routing", "info")
    assert not enabled(spec, SECRET, "debug")


def test_enabled_follows_envfilter_precedence() -> None:
    spec = parse("info,zenoh=debug,zenoh::net=off,zenoh::net::x=trace")
    assert [LEVELS[n] for _, n in spec] == ["info", "debug", "off", "trace"]
    assert enabled(spec, "other", "info") and not enabled(spec, "other", "debug")
    assert enabled(spec, "zenoh::api", "debug") and not enabled(spec, "zenoh::net::y", "error")
    assert enabled(spec, "zenoh::net::x::z", "trace")


SESSION = """
import json, sys, zenoh
import common.bus.rust_log as rust_log
if sys.argv[1] == "uncapped":
    rust_log.SECRET_TARGETS = ()
rust_log.init_zenoh_log()
c = zenoh.Config()
c.insert_json5("mode", '"peer"')
c.insert_json5("scouting/multicast/enabled", "false")
c.insert_json5("listen/endpoints", "[]")
c.insert_json5("transport/auth/usrpwd", json.dumps({"user": "u", "password": "pw-7c1e55"}))
zenoh.open(c).close()
"""


def test_a_real_session_under_trace_logs_the_password_only_without_the_cap() -> None:
    """A Zenoh peer session (no network) with a usrpwd configuration, RUST_LOG=trace."""
    out = {}
    for mode in ("capped", "uncapped"):
        p = subprocess.run([sys.executable, "-c", SESSION, mode], capture_output=True, text=True,
                           timeout=60, env={**os.environ, "RUST_LOG": "trace", "NO_COLOR": "1"})
        assert p.returncode == 0, p.stderr
        out[mode] = p.stdout + p.stderr
    assert "TRACE" in out["capped"] and "pw-7c1e55" not in out["capped"]
    assert "pw-7c1e55" in out["uncapped"]

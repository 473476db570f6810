"""A partitioned deployment (deploy/partitioned, docs/networks.md "Partitions"): what
`pfusion run` starts, the identities and grants of the partitions, and the refusals of
global fusion without its partition."""

from __future__ import annotations

from pathlib import Path

import pytest
import zenoh

from common.deploy.acl import access_control, grants, identity_of
from common.deploy.config import load
from common.deploy.deployment import partitions, plan
from common.wire.radar_chain import global_fusion

DEPLOY = Path(__file__).resolve().parents[2] / "deploy" / "partitioned"


def test_run_starts_one_global_fusion_per_partition() -> None:
    cfg = load(DEPLOY / "fusion.toml")
    assert partitions(cfg) == ("west", "east")
    specs = [s for s in plan(cfg, "F", ("global-fusion",))]
    assert [(s.argv[-2:], s.alive) for s in specs] == [
        (("--partition", "west"), "global_fusion/west"), (("--partition", "east"), "global_fusion/east")]


def test_each_partition_may_publish_its_tracks_and_hand_over_to_the_others_only() -> None:
    cfg = load(DEPLOY / "fusion.toml")
    g = grants(cfg)
    assert "global-fusion" not in g
    assert identity_of("global-fusion", partition="east") == "global-fusion-east"
    west = g["global-fusion-west"]
    assert sorted(west.publish) == ["metrics/global_fusion/west", "radar/gtracks/west",
                                    "radar/handover/east", "radar/handover_ack/east"]
    assert sorted(west.subscribe) == ["radar/etracks/*", "radar/gtracks/east",
                                      "radar/handover/west", "radar/handover_ack/west"]
    assert west.tokens == ["alive/global_fusion/west"]
    assert "radar/gtracks/*" in g["viewer"].subscribe and "radar/gtracks/*" in g["evaluate"].subscribe
    subjects = {s["id"] for s in access_control(cfg)["subjects"]}
    assert {"global-fusion-west", "global-fusion-east"} <= subjects


def test_global_fusion_needs_its_partition_and_only_a_known_one() -> None:
    cfg = load(DEPLOY / "fusion.toml")
    with pytest.raises(ValueError, match="--partition"):
        global_fusion(cfg)
    with pytest.raises(ValueError, match="not one of"):
        global_fusion(cfg, "north")
    assert global_fusion(cfg, "east").bases == tuple(b.id for b in cfg.bases)
    with pytest.raises(ValueError, match="no partition"):
        global_fusion(load(DEPLOY / "site2.toml"), "east")


def allowed(acl: dict, user: str, flow: str, message: str, key: str) -> bool:
    """Whether the generated section lets ``user`` send (ingress) or receive (egress)
    ``message`` on ``key`` (as tests/integration/test_security.py reads it)."""
    rules = {r["id"]: r for r in acl["rules"]}
    return any(flow in r["flows"] and message in r["messages"]
               and any(zenoh.KeyExpr(k).includes(zenoh.KeyExpr(key)) for k in r["key_exprs"])
               for p in acl["policies"] if user in p["subjects"] for r in (rules[i] for i in p["rules"]))


def test_the_generated_access_control_lets_a_partition_use_its_keys_only() -> None:
    acl = access_control(load(DEPLOY / "fusion.toml"))
    root = "pf/v1"
    keys = ["radar/gtracks", "radar/gtracks/west", "radar/gtracks/east", "radar/handover/west",
            "radar/handover/east", "radar/handover_ack/west", "radar/handover_ack/east",
            "radar/etracks/r1dvbt2"]
    put = {u: {k for k in keys if allowed(acl, u, "ingress", "put", f"{root}/{k}")}
           for u in ("global-fusion-west", "global-fusion-east")}
    get = {u: {k for k in keys if allowed(acl, u, "egress", "put", f"{root}/{k}")}
           for u in ("global-fusion-west", "viewer")}
    assert put["global-fusion-west"] == {"radar/gtracks/west", "radar/handover/east",
                                         "radar/handover_ack/east"}
    assert put["global-fusion-east"] == {"radar/gtracks/east", "radar/handover/west",
                                         "radar/handover_ack/west"}
    assert get["global-fusion-west"] == {"radar/gtracks/east", "radar/handover/west",
                                         "radar/handover_ack/west", "radar/etracks/r1dvbt2"}
    assert get["viewer"] == {"radar/gtracks", "radar/gtracks/west", "radar/gtracks/east"}
    assert allowed(acl, "global-fusion-east", "ingress", "liveliness_token",
                   f"{root}/alive/global_fusion/east")
    assert not allowed(acl, "global-fusion-east", "ingress", "liveliness_token",
                       f"{root}/alive/global_fusion/west")

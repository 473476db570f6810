"""ACL of a site's feed tools (docs/security.md, Feeds)."""

from __future__ import annotations

from pathlib import Path

from common.deploy.acl import grants
from common.deploy.config import load


def test_a_site_may_run_the_feed_of_each_of_its_bases_and_no_other() -> None:
    """`pfusion ingest blah2 --base B --identity site-S`: its plots, metrics, liveliness
    token and control queryable for the bases of S only (docs/security.md, Feeds)."""
    cfg = load(Path(__file__).resolve().parents[2] / "deploy" / "secured" / "pfusion.toml")
    every = {b.id for b in cfg.bases}
    for s in cfg.sites:
        g = grants(cfg)[f"site-{s.id}"]
        assert {f"metrics/ingest/{b}" for b in s.bases} <= set(g.publish)
        assert sorted(g.tokens) == sorted(f"alive/ingest/{b}" for b in s.bases)
        assert sorted(g.serve) == sorted(f"control/ingest/{b}" for b in s.bases)
        others = every - set(s.bases)
        assert not [k for k in g.publish + g.tokens + g.serve if k.rsplit("/", 1)[-1] in others]

"""Zenoh identities and access control generated from the deployment (docs/security.md).

Every process logs in to its router with a Zenoh username, its *identity*, derived from
its command and its --base / --array (:func:`identity_of`). :func:`grants` says what
each identity of a deployment may do, and :func:`access_control` turns that into the
``access_control`` section of a Zenoh 1.x router (deny by default): a receiver site
publishes only its bases' plots and its arrays' detections, a service only its output,
metrics and liveliness keys, the read roles ``viewer`` (tracks and status) and
``analyst`` (everything) only read, ``operator-tma`` (``pfusion tma-input``) only
enters TMA bounds, support values and their clearing and reads the TMA solutions and the
tma service's acks, and only ``global-fusion`` publishes ``radar/gtracks`` (in a
partitioned deployment ``global-fusion-<p>`` its ``radar/gtracks/<p>`` and the
handovers and acks to the other partitions, docs/networks.md). Flows are
seen from the router: *ingress* is what a client sends to it, *egress* what it sends to
a client.

Under mutual TLS each identity is also bound to certificates: a subject with both
``usernames`` and ``cert_common_names`` matches only when both do (verified on 1.10.2),
so a password works only with the certificate of a host that runs its identity
([zenoh.tls.hosts]), and ``router-<site>`` only with the certificate of common name
``router-<site>``.

Routers: a site router logs in upstream as ``router-<site>`` and may pass exactly what
the identities of its site may send and receive (:func:`site_members`); the upstream
router is recognised by a site router only by its certificate's common name
``router-fusion`` (mutual TLS: Zenoh's user/password authentication is one-way, the
accepting side checks the connecting one).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any

import zenoh

from common.deploy.config import Config, ConfigError
from common.deploy.deployment import GLOBAL_FUSION, PER_ARRAY, PER_BASE, partitions, token_name

VIEWER = "viewer"
ANALYST = "analyst"
OPERATOR_TMA = "operator-tma"
ROLES = (VIEWER, ANALYST, OPERATOR_TMA)
SIMULATOR = "simulator"
EVALUATE = "evaluate"
ROUTER_FUSION = "router-fusion"
VIEWER_TOOLS = ("status", "run", "export")  # tracks, liveliness and metrics are enough
ANALYST_TOOLS = ("watch", "record", "demo", "view")  # any key: plots, etracks, truth
TEST_FEEDS = ("simulate", "replay")
OPERATOR_TMA_TOOLS = ("tma-input",)
OPERATOR_TMA_PUTS = ("sonar/tma/bounds/*", "sonar/tma/support/*", "sonar/tma/clear/*")
ANALYST_TOKENS = ("alive/record/*", "alive/demo/*")
VIEWER_READS = ("radar/gtracks", "radar/gtracks/*", "sonar/btracks/*", "sonar/tma/*", "metrics/**")
ALL_MESSAGES = ["put", "delete", "declare_subscriber", "query", "reply", "declare_queryable",
                "liveliness_token", "declare_liveliness_subscriber", "liveliness_query"]


@dataclass
class Grant:
    """What one identity may do; key expressions under the deployment's root.

    publish: keys it may put; subscribe: key expressions it may subscribe to (and
    receive); tokens: liveliness tokens it may declare; serve: queryables it may declare
    (and answer); query: key expressions it may query; watch_alive: liveliness queries
    and subscribers on alive/**."""

    publish: list[str] = field(default_factory=list)
    subscribe: list[str] = field(default_factory=list)
    tokens: list[str] = field(default_factory=list)
    serve: list[str] = field(default_factory=list)
    query: list[str] = field(default_factory=list)
    watch_alive: bool = False


def identity_of(command: str, base: str | None = None, array: str | None = None,
                partition: str | None = None) -> str | None:
    """The Zenoh username of ``pfusion COMMAND`` (None: the command needs no identity or
    must be given one, like a router); ``global-fusion-<partition>`` for a partition."""
    if command == GLOBAL_FUSION and partition:
        return f"{command}-{partition}"
    if command in PER_BASE and base:
        return f"{command}-{base}"
    if command in PER_ARRAY and array:
        return f"{command}-{array}"
    if command in (GLOBAL_FUSION, EVALUATE):
        return command
    if command in TEST_FEEDS:
        return SIMULATOR
    if command in VIEWER_TOOLS:
        return VIEWER
    if command in ANALYST_TOOLS:
        return ANALYST
    if command in OPERATOR_TMA_TOOLS:
        return OPERATOR_TMA
    return None


def site_identity(site_id: str) -> str:
    return f"site-{site_id}"


def router_identity(site_id: str) -> str:
    return f"router-{site_id}"


def _service(command: str, instance: str, out: list[str], inputs: list[str]) -> Grant:
    """A service: its outputs, its metrics key, its liveliness token and its control
    queryable (common.bus.control)."""
    name = token_name(command)
    return Grant(publish=[*out, f"metrics/{name}/{instance}"], subscribe=inputs,
                 tokens=[f"alive/{name}/{instance}"], serve=[f"control/{name}/{instance}"])


def grants(cfg: Config) -> dict[str, Grant]:
    """Every identity of the deployment and what it may do (routers excluded)."""
    g: dict[str, Grant] = {}
    for s in cfg.sites:
        g[site_identity(s.id)] = Grant(  # its feeds: `pfusion ingest blah2 --base B` per base
            publish=[f"radar/plots/{b}/*" for b in s.bases]
            + [f"sonar/detections/{a}" for a in s.arrays]
            + [f"metrics/ingest/{b}" for b in s.bases],
            tokens=[f"alive/ingest/{b}" for b in s.bases],
            serve=[f"control/ingest/{b}" for b in s.bases])
    for b in cfg.bases:
        g[f"channel-plotter-{b.id}"] = _service("channel-plotter", b.id, [f"radar/fused/{b.id}"],
                                                [f"radar/plots/{b.id}/*"])
        g[f"elementary-tracker-{b.id}"] = _service("elementary-tracker", b.id,
                                                   [f"radar/etracks/{b.id}"], [f"radar/fused/{b.id}"])
    parts = partitions(cfg)
    for p in parts:  # docs/networks.md, "Partitions"
        others = [o for o in parts if o != p]
        g[f"{GLOBAL_FUSION}-{p}"] = _service(
            GLOBAL_FUSION, p, [f"radar/gtracks/{p}"] + [f"radar/handover/{o}" for o in others]
            + [f"radar/handover_ack/{o}" for o in others],
            ["radar/etracks/*", f"radar/handover/{p}", f"radar/handover_ack/{p}"]
            + [f"radar/gtracks/{o}" for o in others])
    if cfg.bases and not parts:
        g[GLOBAL_FUSION] = _service(GLOBAL_FUSION, "main", ["radar/gtracks"], ["radar/etracks/*"])
    if cfg.bases:
        g[EVALUATE] = _service(EVALUATE, "main", [], ["radar/gtracks", "radar/gtracks/*",
                                                      "sim/truth/radar", "sim/status"])
    for a in cfg.arrays:
        bt = g[f"bearing-tracker-{a.id}"] = _service(
            "bearing-tracker", a.id, [f"sonar/btracks/{a.id}"],
            [f"sonar/detections/{a.id}", f"sonar/tma/{a.id}"])
        bt.serve.append(f"sonar/history/{a.id}/*")
        tma = g[f"tma-{a.id}"] = _service(
            "tma", a.id, [f"sonar/tma/{a.id}", f"sonar/tma/ack/{a.id}"],
            [f"sonar/detections/{a.id}", f"sonar/btracks/{a.id}", f"sonar/tma/bounds/{a.id}",
             f"sonar/tma/support/{a.id}", f"sonar/tma/clear/{a.id}"])
        tma.query = [f"sonar/history/{a.id}/*"]
    g[VIEWER] = Grant(subscribe=list(VIEWER_READS), watch_alive=True)
    g[ANALYST] = Grant(subscribe=["**"], query=["**"], tokens=list(ANALYST_TOKENS),
                       watch_alive=True)
    g[OPERATOR_TMA] = Grant(publish=list(OPERATOR_TMA_PUTS),
                            subscribe=["sonar/tma/*", "sonar/tma/ack/*"])
    g[SIMULATOR] = Grant(publish=["radar/plots/**", "sonar/detections/**", "sim/**"],
                         query=["control/**"],  # replay: which services are ahead, --reset
                         tokens=["alive/simulate/*"], watch_alive=True)
    return g


def site_members(cfg: Config, site_id: str) -> list[str]:
    """Identities whose traffic a site's router forwards: the site's feed, the services
    of its bases and arrays, and the roles (an operator may work at any site)."""
    s = next(s for s in cfg.sites if s.id == site_id)
    out = [site_identity(s.id), *ROLES]
    out += [f"{c}-{b}" for b in s.bases for c in PER_BASE]
    out += [f"{c}-{a}" for a in s.arrays for c in PER_ARRAY]
    return out


def _rule(rid: str, flows: list[str], messages: list[str], root: str, keys: list[str]
          ) -> dict[str, Any]:
    return {"id": rid, "permission": "allow", "flows": flows, "messages": messages,
            "key_exprs": [f"{root}/{k}" for k in keys]}


def _rules(name: str, g: Grant, root: str,
           more: tuple[tuple[str, list[str], list[str], list[str]], ...] = ()
           ) -> list[dict[str, Any]]:
    """The allow rules of one identity, and ``more`` (what, flows, messages, keys) parts
    (empty key lists give no rule)."""
    parts = [
        ("publish", ["ingress"], ["put"], g.publish),
        ("readers", ["egress"], ["declare_subscriber"], ["**"] if g.publish else []),
        ("subscribe", ["ingress"], ["declare_subscriber"], g.subscribe),
        ("receive", ["egress"], ["put"], g.subscribe),
        ("token", ["ingress"], ["liveliness_token"], g.tokens),
        ("serve", ["ingress"], ["declare_queryable", "reply"], g.serve),
        ("asked", ["egress"], ["query"], g.serve),
        ("query", ["ingress"], ["query"], g.query),
        ("answers", ["egress"], ["reply"], g.query),
        ("alive", ["ingress"], ["declare_liveliness_subscriber", "liveliness_query"],
         ["alive/**"] if g.watch_alive else []),
        ("alive-in", ["egress"], ["liveliness_token", "reply"], ["alive/**"] if g.watch_alive else []),
        *more,
    ]
    return [_rule(f"{name}/{what}", flows, msgs, root, keys) for what, flows, msgs, keys in parts
            if keys]


def _router_rules(name: str, members: list[Grant], root: str) -> list[dict[str, Any]]:
    """A site router: what its members may send (ingress) and receive (egress), and the
    declarations a router passes on for them: queryables its members may query, liveliness
    interest in and queries of its members' tokens (answered by it)."""
    def union(attr: str) -> list[str]:
        """The members' keys of ``attr``, without those another one includes."""
        keys = {zenoh.KeyExpr(k) for g in members for k in getattr(g, attr)}
        return sorted(str(k) for k in keys if not any(o != k and o.includes(k) for o in keys))

    u = Grant(publish=union("publish"), subscribe=union("subscribe"), tokens=union("tokens"),
              serve=union("serve"), query=union("query"),
              watch_alive=any(g.watch_alive for g in members))
    return _rules(name, u, root, (
        ("queryables", ["egress"], ["declare_queryable"], u.query),
        ("watchers", ["egress"], ["declare_liveliness_subscriber", "liveliness_query"], u.tokens),
        ("token-replies", ["ingress"], ["reply"], u.tokens)))


def hosts_of(cfg: Config) -> dict[str, list[str]] | None:
    """Identity -> common names of the certificates it may use ([zenoh.tls.hosts]); None
    without mutual TLS (no client certificate to bind to). ConfigError when the table is
    missing or names an unknown identity, a router, or a router's common name."""
    tls = cfg.zenoh.tls
    hosts = tls.hosts if tls is not None else {}
    if tls is None or not tls.mtls:
        if hosts:
            raise ConfigError("zenoh.tls.hosts", "binds identities to client certificates, "
                                                 "which only mutual TLS has: set mtls = true")
        return None
    if not hosts:
        raise ConfigError("zenoh.tls.hosts", "missing: under mutual TLS every identity is bound "
                                             "to the common names of the hosts that run it "
                                             "(docs/security.md)")
    known = grants(cfg)
    routers = {ROUTER_FUSION, *(router_identity(s.id) for s in cfg.sites)}
    out: dict[str, list[str]] = {}
    for cn, names in hosts.items():
        if cn in routers:
            raise ConfigError("zenoh.tls.hosts", f"{cn!r} is a router's common name, not a host's")
        for n in names:
            if n not in known:
                raise ConfigError(f"zenoh.tls.hosts.{cn}", f"{n!r} is not an identity of the "
                                  f"deployment (`pfusion acl` lists them; routers are bound to "
                                  f"their own certificates)")
            out.setdefault(n, []).append(cn)
    return out


def access_control(cfg: Config) -> dict[str, Any]:
    """The router's ``access_control`` section: deny by default, an allow rule set and a
    subject per identity, its username and, under mutual TLS, the common names of its
    hosts (an identity that no host runs gets none: denied); ``router-<site>`` with its
    own common name, and ``router-fusion`` by common name alone."""
    root = cfg.zenoh.root
    g = grants(cfg)
    cns = hosts_of(cfg)
    rules, subjects, policies = [], [], []

    def add(name: str, rs: list[dict[str, Any]], subject: dict[str, Any]) -> None:
        if ":" in name:
            raise ConfigError("site", f"identity {name!r} contains ':' (not allowed in a "
                                      "Zenoh user:password file); rename the base, array or site")
        rules.extend(rs)
        subjects.append({"id": name, **subject})
        policies.append({"id": name, "rules": [r["id"] for r in rs], "subjects": [name]})

    def subject(name: str, names: list[str]) -> dict[str, Any]:
        return {"usernames": [name]} if cns is None else {"usernames": [name],
                                                          "cert_common_names": names}

    for name, grant in g.items():
        if cns is None or name in cns:
            add(name, _rules(name, grant, root), subject(name, cns[name] if cns else []))
    for s in cfg.sites:
        name = router_identity(s.id)
        add(name, _router_rules(name, [g[m] for m in site_members(cfg, s.id) if m in g], root),
            subject(name, [name]))
    if cns is not None:
        add(ROUTER_FUSION, [_rule(f"{ROUTER_FUSION}/all", ["ingress", "egress"], ALL_MESSAGES,
                                  root, ["**"])], {"cert_common_names": [ROUTER_FUSION]})
    return {"enabled": True, "default_permission": "deny", "rules": rules,
            "subjects": subjects, "policies": policies}


def to_json5(acl: dict[str, Any]) -> str:
    """The section as JSON5 text (JSON is JSON5) as ``pfusion acl`` prints it: one rule,
    subject or policy per line."""
    lines = ['{"access_control": {']
    for k, v in acl.items():
        if isinstance(v, list):
            items = ",\n".join(f"    {json.dumps(x)}" for x in v)
            lines.append(f'  "{k}": [\n{items}\n  ],')
        else:
            lines.append(f'  "{k}": {json.dumps(v)},')
    lines[-1] = lines[-1].rstrip(",")
    return "\n".join([*lines, "}}"])

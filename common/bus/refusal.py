"""What a client says when a secured router refuses it or drops what it sends
(docs/security.md, "Audit"): the client sees the same failure whatever the cause, so the
message names the likely causes and where the router's audit names the actual one.
"""

from __future__ import annotations

from common.deploy.config import ZenohConfig


def refusal_causes(zc: ZenohConfig) -> str:
    """Why a secured router may have refused this client, most likely first: what a
    refusal looks like to the client is the same whatever the cause (Zenoh's
    "Unable to connect"), the router's audit line names it (docs/security.md, Audit)."""
    causes = []
    if zc.auth is not None:
        causes.append(f"wrong password for identity '{zc.identity}' in {zc.auth.credentials}, "
                      "or the identity is not in the router's dictionary")
    if zc.tls is not None:
        causes.append(f"the router's certificate is not signed by {zc.tls.root_ca} or does not "
                      "name the address dialled")
        if zc.tls.mtls:
            causes.append(f"this host's certificate {zc.tls.cert} is not signed by the "
                          "deployment's CA or has expired")
    causes.append("the router is not running at that address")
    return ("likely causes: " + "; ".join(causes) + "; the router's log names the refusal "
            "('audit login_failed' or 'audit tls_refused')")


def silence_causes(zc: ZenohConfig) -> str:
    """Why a secured session may receive nothing although it connected: the access control
    drops what it does not allow, without telling the client."""
    return (f"with access control, identity '{zc.identity}' receives and sends only what "
            "'pfusion acl' grants it, and nothing at all when this host's certificate common "
            "name is not bound to it in [zenoh.tls.hosts]; the router's log names each "
            "refusal ('audit denied' or 'audit no_subject')")

"""The validity of a process's own TLS certificate (docs/security.md, "Validity"): one
that has expired is refused (ConfigError: exit 2, which ``pfusion run`` does not
restart), one that expires within WARN_DAYS is logged as a WARNING once per process.

The end date is read with the openssl CLI (``openssl x509 -enddate -noout``): the
``cryptography`` package is not a dependency.
"""

from __future__ import annotations

import logging
import subprocess
from datetime import datetime, timedelta, timezone

from common.deploy.config import ConfigError

WARN_DAYS = 7
log = logging.getLogger("certs")
_warned: set[str] = set()


def not_after(path: str, key: str) -> datetime:
    """The end of ``path``'s validity (a PEM certificate), UTC; ConfigError naming
    ``key`` when openssl cannot read it."""
    try:
        out = subprocess.run(["openssl", "x509", "-enddate", "-noout", "-in", path],
                             capture_output=True, text=True, timeout=30, check=True).stdout
    except FileNotFoundError:
        raise ConfigError(key, "the openssl command is needed to check the certificate's "
                               "validity and was not found") from None
    except subprocess.CalledProcessError as e:
        raise ConfigError(key, f"{path} is not a PEM certificate openssl can read: "
                               f"{' '.join(e.stderr.split())[:200]}") from None
    when = out.strip().partition("=")[2]  # notAfter=Jan  2 00:00:00 2026 GMT
    return datetime.strptime(" ".join(when.split()), "%b %d %H:%M:%S %Y %Z").replace(
        tzinfo=timezone.utc)


def check_validity(path: str, key: str, now: datetime | None = None) -> str:
    """``path`` if its certificate is still valid at ``now`` (default: now); a WARNING,
    once per path and process, when it expires within WARN_DAYS days; ConfigError when
    it has expired."""
    end = not_after(path, key)
    now = now or datetime.now(timezone.utc)
    if end <= now:
        raise ConfigError(key, f"{path} expired on {end:%Y-%m-%d %H:%M} UTC: issue a new "
                               "certificate (docs/security.md, rotation)")
    if end - now <= timedelta(days=WARN_DAYS) and path not in _warned:
        _warned.add(path)
        log.warning("%s (%s) expires on %s UTC, in %.1f days: issue a new one "
                    "(docs/security.md, rotation)", key, path, f"{end:%Y-%m-%d %H:%M}",
                    (end - now).total_seconds() / 86400)
    return path

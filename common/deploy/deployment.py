"""What ``pfusion run`` starts for a deployment, and when it restarts a crashed child.

Pure: builds ``pfusion`` argument lists from a :class:`~common.deploy.config.Config` and keeps
the restart back-off; the process handling is in ``services/run``.
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from dataclasses import dataclass

from common.deploy.config import Config, ConfigError, section
from common.radar.network.params import NetworkParams

PER_BASE = ("channel-plotter", "elementary-tracker")
PER_ARRAY = ("bearing-tracker", "tma")
GLOBAL_FUSION = "global-fusion"
MIN_BASES_FOR_FUSION = 2


def partitions(cfg: Config) -> tuple[str, ...]:
    """The partitions of global fusion ([radar.network] partitions; empty: one instance)."""
    return section(cfg, "radar.network", NetworkParams).partitions if cfg.bases else ()


def token_name(command: str) -> str:
    """The service part of a command's liveliness key (``channel-plotter`` declares
    ``<root>/alive/channel_plotter/<instance>``)."""
    return command.replace("-", "_")


@dataclass(frozen=True)
class ChildSpec:
    """One child process: ``name`` labels its log lines, ``argv`` follows ``pfusion``,
    ``alive`` is the liveliness key (under ``<root>/alive/``) the simulator waits for."""

    name: str
    argv: tuple[str, ...]
    alive: str


def plan(cfg: Config, config_path: str, available: Collection[str],
         connect: Sequence[str] = ()) -> list[ChildSpec]:
    """Every service the deployment describes whose command exists in ``available``:
    a plotter and an elementary tracker per base, global fusion for >= 2 bases (one per
    partition of a partitioned deployment), a bearing tracker and a TMA per array."""
    common = ["--config", config_path]
    for ep in connect:
        common += ["--connect", ep]
    specs: list[ChildSpec] = []
    for base in cfg.bases:
        for cmd in PER_BASE:
            specs.append(ChildSpec(f"{cmd}/{base.id}", (cmd, *common, "--base", base.id),
                                   f"{token_name(cmd)}/{base.id}"))
    if len(cfg.bases) >= MIN_BASES_FOR_FUSION and partitions(cfg):
        specs += [ChildSpec(f"{GLOBAL_FUSION}/{p}", (GLOBAL_FUSION, *common, "--partition", p),
                            f"{token_name(GLOBAL_FUSION)}/{p}") for p in partitions(cfg)]
    elif len(cfg.bases) >= MIN_BASES_FOR_FUSION:
        specs.append(ChildSpec(GLOBAL_FUSION, (GLOBAL_FUSION, *common),
                               f"{token_name(GLOBAL_FUSION)}/*"))
    for array in cfg.arrays:
        for cmd in PER_ARRAY:
            specs.append(ChildSpec(f"{cmd}/{array.id}", (cmd, *common, "--array", array.id),
                                   f"{token_name(cmd)}/{array.id}"))
    return [s for s in specs if s.argv[0] in available]


def simulator_spec(config_path: str, scenario: str, seed: int, speed: float,
                   wait_alive: Sequence[str], connect: Sequence[str] = ()) -> ChildSpec:
    """The simulator, started once every name of ``wait_alive`` is alive."""
    argv = ["simulate", "--config", config_path, "--scenario", scenario,
            "--seed", str(seed), "--speed", repr(float(speed)), "--wait-timeout", "120"]
    for ep in connect:
        argv += ["--connect", ep]
    for name in wait_alive:
        argv += ["--wait-alive", name]
    return ChildSpec("simulate", tuple(argv), "simulate/*")


def router_endpoint(cfg: Config, connect: Sequence[str] | None) -> str:
    """Where ``run --with-router`` listens: the first --connect endpoint, else the first
    ``[zenoh] connect`` endpoint (``tcp/127.0.0.1:7447`` by default), the one where the
    other commands given the same file look for their router."""
    if connect:
        return connect[0]
    if not cfg.zenoh.connect:
        raise ConfigError("zenoh.connect", "is empty: --with-router needs an endpoint to "
                                           "listen on (set it or pass --connect)")
    return cfg.zenoh.connect[0]


def loopback_port(endpoint: str) -> int | None:
    """The port of a ``tcp/127.0.0.1:PORT`` or ``tcp/localhost:PORT`` endpoint, else None."""
    proto, _, addr = endpoint.partition("/")
    host, _, port = addr.rpartition(":")
    if proto != "tcp" or host not in ("127.0.0.1", "localhost") or not port.isdigit():
        return None
    return int(port)


USAGE_EXIT = 2  # a command's code for a configuration or usage error (common.cli)


def restartable(code: int) -> bool:
    """Whether ``pfusion run`` restarts a child that exited with ``code``: not after a
    configuration or usage error (USAGE_EXIT), which would only fail again."""
    return code != USAGE_EXIT


@dataclass
class Backoff:
    """Restart delays: ``first`` doubling up to ``cap``; a child that ran for at least
    ``reset_after`` seconds before it crashed starts again from ``first``."""

    first: float = 0.5
    cap: float = 10.0
    reset_after: float = 30.0
    failures: int = 0

    def next_delay(self, ran_for: float) -> float:
        """Delay before restarting a child that crashed after ``ran_for`` seconds."""
        if ran_for >= self.reset_after:
            self.failures = 0
        delay = min(self.cap, self.first * 2.0 ** self.failures)
        self.failures += 1
        return delay

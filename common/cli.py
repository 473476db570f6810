"""``pfusion``: one command line for every service and tool.

Each command lives in a module with ``add_arguments(parser)`` and ``main(args) -> int``;
the module is imported only when its command runs. An invalid config file or an
unreachable router ends a command with one line on stderr and exit code 2.
"""

from __future__ import annotations

import argparse
import dataclasses
import faulthandler
import importlib
import importlib.metadata
import logging
import re
import signal
import sys

from common.bus import RESTART
from common.deploy.config import Config, ConfigError, load

COMMANDS: dict[str, tuple[str, str]] = {
    "router": ("services.router.main", "run a Zenoh router (Python, no zenohd needed)"),
    "simulate": ("services.simulator.main", "publish a scenario's plots, detections, truth"),
    "watch": ("services.watch.main", "print decoded messages of a key expression live"),
    "demo": ("services.demo.main", "run the built-in scenario end to end and summarise"),
    "params": ("services.params.main", "print the configuration reference or check a file"),
    "bearing-tracker": ("services.bearing_tracker.main", "sonar bearing tracker of one array (000)"),
    "tma": ("services.tma.main", "target motion analysis of one array's confirmed bearing tracks (002, 003)"),
    "tma-input": ("services.tma_input.main",
                  "an operator's TMA bounds or support values for one bearing track, acknowledged"),
    "channel-plotter": ("services.channel_plotter.main", "fuse one base's channel plots (001 modules 31-34)"),
    "elementary-tracker": ("services.elementary_tracker.main", "elementary tracks of one base (001 modules 41-44)"),
    "run": ("services.run.main", "start every service of a deployment, restart crashed ones"),
    "status": ("services.status.main", "list live services and their counters"),
    "record": ("services.record.main", "record messages of key expressions to a .pfrec file"),
    "replay": ("services.replay.main", "republish a .pfrec recording in order"),
    "global-fusion": ("services.global_fusion.main",
                      "global Cartesian tracks from all bases' elementary tracks (001 step 24)"),
    "evaluate": ("services.evaluate.main", "GOSPA/OSPA, switches, breaks, NEES and PCRLB of global tracks vs truth"),
    "acl": ("services.acl.main", "print the Zenoh access control generated from a deployment"),
    "view": ("services.view.main", "live operator view in a browser: tracks, sonar, services"),
    "export": ("services.export.main", "global tracks of a recording or live as GeoJSON for map tools"),
    "ingest": ("services.ingest.main", "plots of external nodes: a blah2 node's HTTP API, or a CSV file"),
}


# One example per command, shown by ``pfusion COMMAND --help`` (tests/integration/test_cli.py parses
# each with the command's own parser).
EXAMPLES: dict[str, str] = {
    "router": "pfusion router --listen tcp/127.0.0.1:7447",
    "simulate": "pfusion simulate --config scenarios/two_targets.toml "
                "--scenario scenarios/two_targets.toml --speed 1",
    "watch": "pfusion watch --config scenarios/two_targets.toml 'radar/gtracks'",
    "demo": "pfusion demo",
    "params": "pfusion params --check scenarios/two_targets.toml",
    "bearing-tracker": "pfusion bearing-tracker --config scenarios/sonar_tma.toml --array a1",
    "tma": "pfusion tma --config scenarios/sonar_tma.toml --array a1",
    "tma-input": "pfusion tma-input bounds --config scenarios/sonar_tma.toml --array a1 --track 1 "
                 "--course-min 200 --course-max 300 --speed-min 2 --speed-max 6",
    "channel-plotter": "pfusion channel-plotter --config scenarios/two_targets.toml --base b1",
    "elementary-tracker": "pfusion elementary-tracker --config scenarios/two_targets.toml --base b1",
    "run": "pfusion run --config scenarios/two_targets.toml --with-router",
    "status": "pfusion status --config scenarios/two_targets.toml --watch",
    "record": "pfusion record --config scenarios/two_targets.toml 'radar/plots/**' --out run.pfrec",
    "replay": "pfusion replay --config scenarios/two_targets.toml run.pfrec --speed 1",
    "global-fusion": "pfusion global-fusion --config scenarios/two_targets.toml",
    "evaluate": "pfusion evaluate --config scenarios/two_targets.toml",
    "acl": "pfusion acl --config scenarios/two_targets.toml",
    "view": "pfusion view --config scenarios/two_targets.toml --port 8080",
    "export": "pfusion export --config scenarios/geodetic_two_targets.toml --recording run.pfrec "
              "--geojson tracks.geojson",
    "ingest": "pfusion ingest blah2 --config scenarios/network_rd.toml --base r1fm1 --url http://127.0.0.1:3000",
}


def add_common(p: argparse.ArgumentParser, config_required: bool = True) -> None:
    """--config, --connect and --log-level, shared by every service."""
    p.add_argument("--config", required=config_required, help="deployment TOML file")
    p.add_argument(
        "--connect", action="append", default=None,
        help="Zenoh endpoint to connect to, e.g. tcp/127.0.0.1:7447 (overrides [zenoh])",
    )
    p.add_argument("--identity", help="Zenoh username under [zenoh.auth] (default: from the "
                                      "command, --base, --array; docs/security.md)")


def add_base_service(p: argparse.ArgumentParser) -> None:
    """The arguments of a per-base radar service: add_common and --base."""
    add_common(p)
    p.add_argument("--base", required=True, help="bistatic base id (a [[radar.base]] id)")


def load_config(args: argparse.Namespace) -> Config:
    """The deployment config of ``args`` (every table checked), with --connect applied
    and the process's Zenoh identity (--identity, else common.deploy.acl.identity_of)."""
    from common.deploy.acl import identity_of
    from common.deploy.sections import check_all

    cfg = load(args.config) if args.config else _empty_config()
    check_all(cfg)
    z = cfg.zenoh
    if args.connect:
        z = dataclasses.replace(z, connect=args.connect, listen=[])
    identity = getattr(args, "identity", None) or identity_of(
        getattr(args, "pfusion_command", ""), getattr(args, "base", None), getattr(args, "array", None),
        getattr(args, "partition", None))
    return dataclasses.replace(cfg, zenoh=dataclasses.replace(z, identity=identity))


def _empty_config() -> Config:
    from common.deploy.config import parse

    return parse({})


def _zenoh_error() -> type[Exception]:
    """``zenoh.ZError``, imported only once a command has failed (``params`` never loads
    Zenoh)."""
    import zenoh

    return zenoh.ZError


def one_line(e: Exception) -> str:
    """An exception's message on one line, without the Rust source locations of Zenoh's."""
    return " ".join(re.sub(r" at /\S+\.rs:\d+\.?", "", str(e)).split())


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="pfusion", description=__doc__.splitlines()[0].replace("``", ""),
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="examples:\n  " + "\n  ".join(EXAMPLES[c] for c in ("run", "watch", "status"))
               + "\n\n'pfusion COMMAND --help' shows the options and an example of each command.",
    )
    parser.add_argument("--version", action="version",
                        version=f"%(prog)s {importlib.metadata.version('passive-fusion')}")
    parser.add_argument("--log-level", default="INFO", help="DEBUG, INFO, WARNING, ERROR")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name, (_, help_) in COMMANDS.items():
        sub.add_parser(name, help=help_, add_help=False)
    pre, rest = parser.parse_known_args(argv)
    module = importlib.import_module(COMMANDS[pre.command][0])
    cmd = argparse.ArgumentParser(prog=f"pfusion {pre.command}", description=COMMANDS[pre.command][1],
                                  formatter_class=argparse.RawDescriptionHelpFormatter,
                                  epilog=f"example:\n  {EXAMPLES[pre.command]}")
    module.add_arguments(cmd)
    cmd.set_defaults(pfusion_command=pre.command)
    args = cmd.parse_args(rest)
    logging.basicConfig(
        level=pre.log_level.upper(),
        format="%(asctime)s %(levelname)s %(name)s: %(message)s",
        stream=sys.stderr,
    )
    # a hung process's stacks, on demand, to the process's own stderr (sys.stderr may be
    # a test's capture, without a file descriptor)
    faulthandler.register(signal.SIGUSR1, file=sys.__stderr__, all_threads=True)
    try:
        while (code := int(module.main(args) or 0)) == RESTART:  # a reset command (common.bus.service)
            pass
        return code
    except ConfigError as e:
        print(f"pfusion {pre.command}: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130
    except _zenoh_error() as e:
        print(f"pfusion {pre.command}: {one_line(e)}", file=sys.stderr)
        return 2

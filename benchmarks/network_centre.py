"""The fusion centre alone, through its process (issue 29 section 3, docs/networks.md
"Through the processes").

Run: PYTHONPATH=. .venv/bin/python benchmarks/network_centre.py [--scenes 300 1000]
     [--seed 1] [--duration 120] [--speed 0] [--core N] [--cache DIR] [--goal 2]

1. The elementary tracks of every base of a goal scene (benchmarks/network_scene.py:
   8 receivers, 21 range-Doppler bases), made in this process by the real channel
   plotters and elementary trackers (common.wire.radar_chain) from the simulator's
   plots, written as a recording of radar/etracks/<base> (pfusion record's format, each
   payload the elementary-tracker service's message), cached in DIR.
2. A real router and the real `pfusion global-fusion` service on loopback; the service's
   process, every thread, pinned to one core (--core, default the last one this process
   may use; benchmarks/procstat.py); router, replay and this process on the others.
   `pfusion replay` republishes the recording as fast as the service takes it
   (--speed 0: the service's queue holds what it has not processed yet) or at --speed
   times the recorded pace.
3. Measured: the service's CPU time (all threads, /proc/<pid>/stat) and wall time from
   the replay's start until its control queryable (common.bus.control), answered from
   the service's loop after every sample queued before the query (one query at a time,
   never timed out: a reply to an expired query would count as the service's error),
   counts every report in; scene seconds per CPU second (x real time) and per wall second. Nothing lost:
   the service's `in` equals the reports replayed, no sample missed (publisher stamps)
   and none rejected; after SIGTERM (the service flushes its window) the radar/gtracks
   received miss no stamp and the last one is within a report period of the last
   report's time.
Exit 1 when a report is lost, or when the largest scene runs below --goal x real time
(CPU) on its core.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from benchmarks.network_scene import scene_toml  # noqa: E402
from benchmarks.procstat import cpu_seconds, host_load, pin  # noqa: E402
from common.bus.local_run import ROOT, Collector  # noqa: E402
from common.bus.procs import Child, start_router  # noqa: E402
from common.bus.recording import RecordWriter  # noqa: E402
from common.bus.transport import open_session  # noqa: E402
from common.deploy.config import ZenohConfig, load  # noqa: E402
from common.sim.scenario import load_scenario  # noqa: E402
from common.wire import protocol  # noqa: E402
from common.wire.radar_chain import RadarChain  # noqa: E402
from common.wire.radar_messages import etracks_message, plots_of  # noqa: E402
from common.wire.sim_messages import run_scenario  # noqa: E402

SERVICE = ("global_fusion", "main")
REPORT_PERIOD = 1.0  # s: NetworkParams.report_period of the goal scenes
STOP_TIMEOUT = 900.0  # s: the flush at stop, on a loaded machine
QUERY_TIMEOUT = 3600.0  # s: a control query waits in the service's queue behind the reports


def record_etracks(scene: Path, seed: int, out: Path) -> tuple[int, float]:
    """The etracks recording of `scene` (module doc, 1.); returns (reports, the last
    report's message time)."""
    cfg = load(scene)
    chain = RadarChain(cfg)
    part = out.with_suffix(".part")
    n, first, last, t_last = 0, None, 0.0, 0.0
    with part.open("wb") as f:
        w = RecordWriter(f, ROOT, time.time())
        for _, msgs in run_scenario(load_scenario(cfg.doc), cfg.bases, cfg.arrays, seed):
            for key, msg in msgs:
                if not key.startswith("radar/plots/"):
                    continue
                b = msg["base"]
                for t, fused in chain.plotters[b].push(msg["channel"], msg["t"],
                                                       plots_of(msg, chain.azimuth[b])):
                    tracks = chain.trackers[b].step(t, fused)
                    first = t if first is None else first
                    last, t_last = max(last, t - first), max(t_last, t)
                    w.write(f"{ROOT}/radar/etracks/{b}", last,
                            protocol.encode(etracks_message(b, tracks)))
                    n += 1
    part.rename(out)
    return n, t_last


def cached(aircraft: int, seed: int, duration: float, cache: Path) -> tuple[Path, Path, int, float]:
    """(scene file, recording, reports, last report's time) of a goal scene, recorded
    once per cache."""
    cache.mkdir(parents=True, exist_ok=True)
    name = f"network_goals_{aircraft}_s{seed}_{duration:g}s"
    scene, rec, count = cache / f"{name}.toml", cache / f"{name}.pfrec", cache / f"{name}.count"
    if not (rec.exists() and count.exists()):
        scene.write_text(scene_toml(aircraft, seed=seed, duration=duration))
        c0 = time.process_time()
        n, t_last = record_etracks(scene, seed, rec)
        count.write_text(f"{n} {t_last!r}")
        print(f"# recorded {n} etracks reports of {aircraft} aircraft in "
              f"{time.process_time() - c0:.0f} s CPU: {rec}", flush=True)
    n, t_last = count.read_text().split()
    return scene, rec, int(n), float(t_last)


def control(session: Any, timeout: float) -> dict[str, Any] | None:
    """The global-fusion service's control reply (its counters), None without one."""
    for r in session.get(f"{ROOT}/control/{SERVICE[0]}/{SERVICE[1]}", timeout=timeout):
        if r.ok is not None:
            return protocol.unpack(r.ok.payload.to_bytes())
    return None


def wait_alive(session: Any, child: Child, timeout: float = 60.0) -> None:
    deadline = time.monotonic() + timeout
    while not any(r.ok for r in session.liveliness().get(f"{ROOT}/alive/{SERVICE[0]}/{SERVICE[1]}",
                                                         timeout=1.0)):
        if not child.alive() or time.monotonic() > deadline:
            raise RuntimeError(f"global-fusion not alive (log: {child.name}.log)")
        time.sleep(0.1)


@dataclass
class Row:
    """One scene through the service."""

    aircraft: int
    reports: int
    scene_s: float
    cpu_s: float
    wall_s: float
    lost: list[str]
    gtracks: int
    load: str

    @property
    def x_cpu(self) -> float:
        return self.scene_s / max(self.cpu_s, 1e-9)

    @property
    def x_wall(self) -> float:
        return self.scene_s / max(self.wall_s, 1e-9)


def run_centre(aircraft: int, scene: Path, rec: Path, reports: int, t_last: float,
               scene_s: float, args: argparse.Namespace, logdir: Path
               ) -> tuple[Row, list[dict[str, Any]]]:
    """Module doc, 2. and 3.: the row and the radar/gtracks messages received."""
    core = args.core if args.core is not None else max(os.sched_getaffinity(0))
    others = (os.sched_getaffinity(0) - {core}) or {core}
    router, endpoint = start_router(log=logdir / "router.log")
    fusion = replay = None
    session = open_session(ZenohConfig([endpoint], [], ROOT))
    try:
        gtracks = Collector(session, "bench/centre")
        gtracks.subscribe("radar/gtracks")
        pin(router.proc.pid, others)
        pin(os.getpid(), others)
        fusion = Child("global-fusion", "global-fusion", "--config", str(scene), "--connect",
                       endpoint, log=logdir / "global-fusion.log")
        wait_alive(session, fusion)
        pid = fusion.proc.pid
        pin(pid, {core})
        cpu0, wall0, lost = cpu_seconds(pid), time.monotonic(), []
        replay = Child("replay", "replay", str(rec), "--connect", endpoint, "--speed",
                       repr(args.speed), log=logdir / "replay.log")
        pin(replay.proc.pid, others)
        state: dict[str, Any] | None = None
        while state is None or state["in"] < reports:
            if not fusion.alive():
                raise RuntimeError(f"global-fusion exited (log: {logdir})")
            if replay.proc.poll() not in (None, 0):
                raise RuntimeError(f"replay exited with {replay.proc.poll()} (log: {logdir})")
            state = control(session, timeout=QUERY_TIMEOUT) or state
            gtracks.drain()
            time.sleep(0.2)
        cpu, wall = cpu_seconds(pid) - cpu0, time.monotonic() - wall0
        if state["in"] != reports:
            lost.append(f"in {state['in']} of {reports}")
        lost += [f"missed {k}: {v}" for k, v in state["missed"].items() if v]
        lost += [f"rejected {k}: {v}" for k, v in state["rejected"].items() if v]
        code = fusion.stop(timeout=STOP_TIMEOUT)  # it flushes its window: seconds of CPU
        if code != 0:
            lost.append(f"global-fusion exited with {code} at stop")
        deadline = time.monotonic() + 30.0
        while (time.monotonic() < deadline and
               max((m["t"] for m in gtracks.of("radar/gtracks")), default=0.0) < t_last - REPORT_PERIOD):
            time.sleep(0.05)
        msgs = gtracks.of("radar/gtracks")
        lost += [f"gtracks missed {k}: {v}" for k, v in gtracks.losses.missed.items() if v]
        if not msgs:
            lost.append("no gtracks")
        elif max(m["t"] for m in msgs) < t_last - REPORT_PERIOD:
            lost.append(f"last gtracks at {max(m['t'] for m in msgs):.1f} s of {t_last:.1f} s")
        return Row(aircraft, reports, scene_s, cpu, wall, lost, len(msgs), host_load()), msgs
    finally:
        for c in (replay, fusion):
            if c is not None:
                c.stop()
        session.close()
        router.stop()


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenes", type=int, nargs="+", default=[300, 1000], help="aircraft per scene")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--duration", type=float, default=120.0, help="scene seconds")
    ap.add_argument("--speed", type=float, default=0.0,
                    help="replay pace, times real time (0: as fast as the service takes it)")
    ap.add_argument("--core", type=int, default=None, help="the core of global fusion")
    ap.add_argument("--cache", type=Path, default=Path(tempfile.gettempdir()) / "pfusion-network-centre")
    ap.add_argument("--goal", type=float, default=2.0, help="x real time required at the largest scene")
    a = ap.parse_args(argv)
    rows = []
    print(f"{'aircraft':>8} {'reports':>7} {'scene s':>7} {'cpu s':>7} {'x rt cpu':>8} "
          f"{'wall s':>7} {'x rt wall':>9} {'gtracks':>7}  lost; load")
    for n in a.scenes:
        scene, rec, reports, t_last = cached(n, a.seed, a.duration, a.cache)
        with tempfile.TemporaryDirectory(prefix="centre-") as logdir:
            row, _ = run_centre(n, scene, rec, reports, t_last, a.duration, a, Path(logdir))
        rows.append(row)
        print(f"{n:>8} {row.reports:>7} {row.scene_s:>7.0f} {row.cpu_s:>7.1f} {row.x_cpu:>8.2f} "
              f"{row.wall_s:>7.1f} {row.x_wall:>9.2f} {row.gtracks:>7}  "
              f"{', '.join(row.lost) or 'none'}; {row.load}", flush=True)
    lost = any(r.lost for r in rows)
    fast = rows[-1].x_cpu >= a.goal
    print(f"goal: {a.goal:g} x real time at {rows[-1].aircraft} aircraft on one core:",
          "met" if fast else "FAILED", "; nothing lost" if not lost else "; reports LOST")
    return 0 if fast and not lost else 1


if __name__ == "__main__":
    sys.exit(main())

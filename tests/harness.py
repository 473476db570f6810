"""The repository's paths for tests, and the multi-process harness they use
(common.bus.local_run: a real router and real services on loopback ports)."""

from __future__ import annotations

from pathlib import Path

from common.bus.local_run import ROOT, Deployment

REPO = Path(__file__).resolve().parents[1]
SCENARIOS = REPO / "scenarios"

__all__ = ["REPO", "ROOT", "SCENARIOS", "Deployment"]

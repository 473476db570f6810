"""Parsers of the simulator's ground-truth messages (docs/protocol.md, sim/truth/*)."""

from __future__ import annotations

from typing import Any

import numpy as np


def truth_state(m: dict[str, Any]) -> np.ndarray:
    """Truth states (n, 6) [x vx y vy z vz] of a sim/truth/radar message."""
    return np.column_stack([m["x"], m["vx"], m["y"], m["vy"], m["z"], m["vz"]])

"""The operator's TMA inputs of one array kept in a file across restarts of ``pfusion tma``
(``[sonar.tma] state_dir``): JSON of common.sonar.tma.operator_inputs' state, written
atomically (a temporary file renamed over the old one) whenever it changed."""

from __future__ import annotations

import json
import os
from pathlib import Path

from common.bus.service import Service
from common.core.rejection import Rejected
from common.sonar.tma.manager import TmaManager
from common.sonar.tma.operator_inputs import OperatorInputs


class StateFile:
    """<state_dir>/tma-<array>.json, or nothing when ``state_dir`` is empty."""

    def __init__(self, state_dir: str, array: str, svc: Service) -> None:
        self.path = Path(state_dir) / f"tma-{array}.json" if state_dir else None
        self.svc = svc

    def load(self, mgr: TmaManager) -> None:
        """The kept inputs into ``mgr`` (none kept: nothing; unreadable: logged, counted
        as ``bad_state`` and left aside, the service starts without them)."""
        if self.path is None or not self.path.exists():
            return
        try:
            mgr.restore(OperatorInputs.from_state(json.loads(self.path.read_text())))
        except Rejected as e:
            self.svc.reject(e.reason, f"{self.path}: {e.detail}", str(self.path))
            return
        except (OSError, ValueError) as e:  # unreadable file, not JSON
            self.svc.reject("bad_state", f"{self.path}: {e}", str(self.path))
            return
        self.svc.log.info("TMA inputs of %d tracks read from %s", len(mgr.inputs.inputs), self.path)

    def save(self, mgr: TmaManager) -> None:
        """Write the inputs if they changed since the last write (a failed write is
        logged and counted as ``state_write``, and tried again at the next change)."""
        if self.path is None or not mgr.inputs.changed:
            return
        tmp = self.path.with_suffix(".tmp")
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            tmp.write_text(json.dumps(mgr.inputs.state()))
            os.replace(tmp, self.path)
        except OSError as e:
            self.svc.reject("state_write", f"{self.path}: {e}", str(self.path))
            return
        mgr.inputs.changed = False

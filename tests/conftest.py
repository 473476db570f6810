"""Test layout: tests/<package>/ mirrors common/<package>/ (pure unit tests, no network);
tests/integration/ starts real processes (router, services) on loopback ports and is
marked ``integration``; tests over ~15 s carry ``slow``. ``pytest -m "not integration"``
runs the unit tests alone; ``-m "not slow"`` leaves out the long ones."""

from __future__ import annotations

from pathlib import Path

import pytest

INTEGRATION = Path(__file__).resolve().parent / "integration"


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Mark every test under tests/integration/ as ``integration``."""
    for item in items:
        if INTEGRATION in Path(item.fspath).resolve().parents:
            item.add_marker(pytest.mark.integration)

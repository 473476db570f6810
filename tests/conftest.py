"""Test layout: tests/<package>/ mirrors common/<package>/ (pure unit tests, no network);
tests/integration/ starts real processes (router, services) on loopback ports and is
marked ``integration``; tests over ~15 s carry ``slow`` and run first, so that the two
xdist workers do not end on a long test (``make test``: ``--dist loadgroup``; a module
whose module-scoped fixture starts processes is one ``xdist_group``, so that fixture runs
once). ``pytest -m "not integration"`` runs the unit tests alone."""

from __future__ import annotations

from pathlib import Path

import pytest

INTEGRATION = Path(__file__).resolve().parent / "integration"


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Mark every test under tests/integration/ as ``integration``; ``slow`` ones first."""
    for item in items:
        if INTEGRATION in Path(item.fspath).resolve().parents:
            item.add_marker(pytest.mark.integration)
    items.sort(key=lambda item: item.get_closest_marker("slow") is None)

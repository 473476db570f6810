"""tests.netns.require: a namespace test skips where namespaces cannot be made, and
fails there when CI is set (.ci/run sets CI=true), so that CI never skips one."""

from __future__ import annotations

import pytest

from tests import netns


@pytest.mark.parametrize("ci, outcome", [("true", pytest.fail.Exception),
                                         ("1", pytest.fail.Exception),
                                         ("", pytest.skip.Exception),
                                         ("false", pytest.skip.Exception)])
def test_require_fails_under_ci_and_skips_elsewhere(
        monkeypatch: pytest.MonkeyPatch, ci: str, outcome: type[BaseException]) -> None:
    monkeypatch.setattr(netns, "unavailable", lambda: "no namespaces here")
    monkeypatch.setenv("CI", ci)
    with pytest.raises(outcome) as e:
        netns.require()
    assert "no namespaces here" in str(e.value)


def test_require_passes_where_namespaces_can_be_made(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(netns, "unavailable", lambda: None)
    monkeypatch.setenv("CI", "true")
    netns.require()


def test_ci_run_sets_ci() -> None:
    assert "export CI=true" in (netns.REPO / ".ci" / "run").read_text()

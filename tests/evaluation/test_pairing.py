"""common.evaluation.pairing: truth and tracks of one time are scored once, in time order."""

from __future__ import annotations

import pytest

from common.core.rejection import Rejected
from common.evaluation.pairing import StepPairing


def test_a_step_is_paired_whichever_key_comes_first() -> None:
    p: StepPairing[str, str] = StepPairing()
    assert p.truth(1.0, "m1") is None
    assert p.tracks(1.0, "g1") == (1.0, "m1", "g1")
    assert p.tracks(2.0, "g2") is None
    assert p.truth(2.0, "m2") == (2.0, "m2", "g2")


def test_a_step_not_after_the_last_scored_one_is_rejected_not_dropped() -> None:
    p: StepPairing[str, str] = StepPairing()
    p.truth(3.0, "m3")
    p.tracks(3.0, "g3")
    p.truth(2.0, "m2")
    with pytest.raises(Rejected) as e:
        p.tracks(2.0, "g2")
    assert e.value.reason == "out_of_order"
    p.truth(4.0, "m4")
    assert p.tracks(4.0, "g4") == (4.0, "m4", "g4")

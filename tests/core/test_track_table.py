"""TrackTable: number recycling (smallest free first), growth, columns."""

import numpy as np
import pytest

from common.core.track_table import Status, TrackTable


def test_numbers_recycled_smallest_first():
    tt = TrackTable(state_dim=5, capacity=4)
    idx = tt.add(4)
    np.testing.assert_array_equal(tt.ids, [1, 2, 3, 4])
    tt.remove(idx[[1, 3]])  # numbers 2 and 4 released
    np.testing.assert_array_equal(tt.ids, [1, 3])
    assert len(tt) == 2
    new = tt.add(1)
    assert tt.id[new[0]] == 2  # smallest free number first
    new = tt.add(2)
    np.testing.assert_array_equal(tt.id[new], [4, 5])
    np.testing.assert_array_equal(np.sort(tt.ids), [1, 2, 3, 4, 5])


def test_numbers_stable_while_others_change():
    tt = TrackTable(state_dim=2, capacity=2)
    a = tt.add(3)
    kept = tt.id[a[2]]
    tt.remove(a[:2])
    tt.add(5)
    assert tt.id[a[2]] == kept
    assert tt.status[a[2]] == Status.TENTATIVE


def test_add_resets_columns_and_grows():
    tt = TrackTable(state_dim=3, capacity=1, extra={"base": ((), np.int32), "w": ((2,), float)})
    i = tt.add(1)
    tt.score[i] = 7.0
    tt.n_updates[i] = 3
    tt.n_coast[i] = 2
    tt.t_last[i] = 12.5
    tt.x[i] = 1.0
    tt.P[i] = np.eye(3)
    tt.base[i] = 4
    tt.status[i] = Status.CONFIRMED
    tt.remove(i)
    j = tt.add(3)
    assert tt.capacity >= 3
    assert j[0] == i[0]
    assert tt.score[j[0]] == 0 and tt.n_updates[j[0]] == 0 and tt.n_coast[j[0]] == 0
    assert np.isnan(tt.t_last[j[0]]) and not tt.x[j[0]].any() and not tt.P[j[0]].any()
    assert tt.base[j[0]] == 0 and tt.w.shape == (tt.capacity, 2)
    assert tt.x.shape == (tt.capacity, 3) and tt.P.shape == (tt.capacity, 3, 3)
    assert np.all(tt.status[j] == Status.TENTATIVE)


def test_alive_mask_and_index_of():
    tt = TrackTable(state_dim=2)
    idx = tt.add(3)
    tt.status[idx[0]] = Status.COASTING
    tt.remove(idx[1])
    np.testing.assert_array_equal(tt.active_indices(), idx[[0, 2]])
    assert tt.alive.sum() == 2
    np.testing.assert_array_equal(tt.index_of([3, 1]), idx[[2, 0]])
    with pytest.raises(KeyError):
        tt.index_of([2])
    with pytest.raises(KeyError):
        tt.index_of([999])


def test_status_codes():
    assert [int(s) for s in Status] == [0, 1, 2, 3]
    assert Status(2) is Status.COASTING

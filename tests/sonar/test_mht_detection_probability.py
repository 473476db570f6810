"""000 P_D from the predicted amplitude (erfc law), common.sonar.bearing.model."""

import math

import numpy as np
from scipy.stats import norm

from common.sonar.bearing.model import detection_probability


def test_pd_at_threshold_is_half_of_pd_max():
    assert detection_probability(10.0, 2.0, 0.9, 10.0) == 0.45


def test_pd_equals_gaussian_exceedance_probability_times_pd_max():
    a = np.array([0.0, 8.0, 12.0, 20.0])
    sig = np.array([1.0, 2.0, 3.0, 0.5])
    expected = 0.95 * norm.sf(10.0, loc=a, scale=sig)
    np.testing.assert_allclose(detection_probability(a, sig, 0.95, 10.0), expected, rtol=1e-12)


def test_pd_hand_value_one_sigma_above_threshold():
    # erfc(-1/sqrt 2) = 1 + erf(1/sqrt 2) = 1.682689...
    got = detection_probability(12.0, 2.0, 1.0, 10.0)
    assert math.isclose(got, 0.5 * (1.0 + math.erf(1.0 / math.sqrt(2.0))), rel_tol=1e-12)


def test_pd_is_monotone_and_bounded_by_pd_max():
    a = np.linspace(-20.0, 40.0, 200)
    pd = detection_probability(a, 1.5, 0.8, 10.0)
    assert np.all(np.diff(pd) >= 0.0)
    assert pd[0] < 1e-9 and 0.8 - pd[-1] < 1e-9 and np.all(pd <= 0.8)

"""Measurement models of the elementary tracker (seed 001, modules 41-44): the state a
base's tracks carry and what its fused plots measure.

AZIMUTH (001 as written): x = [r_b, v_b, gamma_b, theta, omega], y = [r_b, v_b, theta];
F [19], Q [20], H [11], [22], chi-square(3) gate; crossing management (004) on
(r_b, theta).

RANGE_DOPPLER (a base with an omnidirectional antenna, no theta): x = [r_b, v_b,
gamma_b], y = [r_b, v_b]; F [19] and Q [20] restricted to their range block (the
(theta, omega) block is uncoupled from it, so the restriction is exact),
H = [[1, 0, 0], [0, 1, 0]], chi-square(2) gate; crossing management on (r_b, v_b)
instead of (r_b, theta), a stated deviation (docs/equations.md).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from common.core.angles import TWO_PI
from common.core.motion import bistatic_F, bistatic_Q

VB_SPAN = 1200.0  # m/s: the v_b extent of the 004 domain of a range-Doppler base (+-600 m/s)


@dataclass(frozen=True)
class MeasurementModel:
    """State and measurement of one kind of base.

    n: state dimension. H: (m, n) measurement matrix. meas: state components H observes.
    angles: measurement components that are angles (wrapped innovations).
    wrap: state components kept in [0, 2pi). cross: the measurement components of the
    004 test (a state component meas[c] each). volume_scale: the 004 domain volume of
    this model over [radar.crossing] volume, which is given for (r_b, theta).
    """

    azimuth: bool
    n: int
    H: np.ndarray
    meas: tuple[int, ...]
    angles: tuple[int, ...]
    wrap: tuple[int, ...]
    cross: tuple[int, int]
    volume_scale: float

    @property
    def m(self) -> int:
        """Measurement dimension (the gate's chi-square degrees of freedom)."""
        return int(self.H.shape[0])

    @property
    def cross_angles(self) -> list[int]:
        """Components of the 004 pair (r_b, .) that lie on the circle."""
        return [k for k, c in enumerate(self.cross) if c in self.angles]

    def F(self, T: ArrayLike) -> np.ndarray:
        """001 [19], restricted to the first n state components."""
        return bistatic_F(T)[..., : self.n, : self.n]

    def Q(self, T: ArrayLike, sigma_gamma: float, sigma_omega: float) -> np.ndarray:
        """001 [20], restricted to the first n state components."""
        return bistatic_Q(T, sigma_gamma, sigma_omega)[..., : self.n, : self.n]


AZIMUTH = MeasurementModel(
    azimuth=True, n=5,
    H=np.array([[1, 0, 0, 0, 0], [0, 1, 0, 0, 0], [0, 0, 0, 1, 0]], dtype=float),  # 001 [11], [22]
    meas=(0, 1, 3), angles=(2,), wrap=(3,), cross=(0, 2), volume_scale=1.0)
RANGE_DOPPLER = MeasurementModel(
    azimuth=False, n=3, H=np.array([[1, 0, 0], [0, 1, 0]], dtype=float),
    meas=(0, 1), angles=(), wrap=(), cross=(0, 1), volume_scale=VB_SPAN / TWO_PI)


def model_of(azimuth: bool) -> MeasurementModel:
    """The model of a base declared `azimuth = true / false`."""
    return AZIMUTH if azimuth else RANGE_DOPPLER

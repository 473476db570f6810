"""A range-Doppler node's detections in this project's plot units, and their sigmas.

blah2-style nodes report the bistatic delay as the bistatic range minus the baseline,
in km, and the Doppler shift in Hz:

    r_b = 1000 delay + L        L = ||X_Tx - X_Rx|| (the baseline; the local ENU frame
                                is a rigid motion of ECEF, so it is the ECEF distance)
    v_b = -lambda f_d           lambda = c / fc (an approaching target, f_d > 0, closes)

Sigmas (the plots' diagonal R, 001 [4]), from the cell of the range-Doppler map:

    sigma = bin / sqrt(12) * max(floor, 10^(-(snr - snr_ref) / 20))

with bin = c / fs for r_b (one delay sample) and lambda / CPI for v_b (one Doppler bin,
1 / CPI Hz): the uniform error within a bin at the detection threshold snr_ref,
shrinking as 1 / sqrt(SNR) (peak interpolation) above it, never below `floor` of it;
without an SNR the factor is 1. `srb`, `svb` > 0 replace the derived sigmas.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from common.core.params import Params, Range, non_negative, positive, unbounded

C = 299_792_458.0  # m/s


@dataclass(frozen=True)
class IngestParams(Params):
    """Parameters of table [radar.ingest], overridden key by key per base by
    [radar.ingest.<base>] (the ingest of a node's detections, docs/networks.md).

    fc: carrier (Hz); 0: the node's (`capture.fc` of its /api/config); a value given is
        checked against the node's (1 kHz).
    fs: sample rate (Hz), whose sample c / fs is the range bin; 0: the node's.
    cpi: coherent processing interval (s), whose inverse is the Doppler bin; the node's
        `process.data.cpi` when it reports one.
    time_offset: added to the node's stamps (s): blah2 stamps the start of processing,
        not the CPI centre (-cpi / 2 puts it there, if the CPI ends when processing
        starts), plus any known offset of the node's clock.
    srb, svb: fixed sigmas of r_b (m) and v_b (m/s); 0: derived from the bins and SNR.
    snr_ref: SNR at which a sigma is the bin / sqrt(12) (dB): the detection threshold.
    floor: smallest factor of bin / sqrt(12) a high SNR reaches.
    """

    fc: float = 0.0
    fs: float = 0.0
    cpi: float = 0.5
    time_offset: float = 0.0
    srb: float = 0.0
    svb: float = 0.0
    snr_ref: float = 12.0
    floor: float = 0.25

    RANGES: ClassVar[dict[str, Range]] = {
        "fc": non_negative("Hz"), "fs": non_negative("Hz"), "cpi": positive("s"),
        "time_offset": unbounded("s", "a clock offset of either sign"),
        "srb": non_negative("m"), "svb": non_negative("m/s"),
        "snr_ref": unbounded("dB", "a threshold in dB"), "floor": Range("", 0.0, 1.0, "(]"),
    }


def wavelength(fc: float) -> float:
    """lambda = c / fc (m)."""
    return C / fc


def delay_to_rb(delay_km: np.ndarray, baseline: float) -> np.ndarray:
    """r_b = 1000 delay + L (m) of delays in km (bistatic range minus the baseline)."""
    return 1000.0 * np.asarray(delay_km, dtype=float) + baseline


def doppler_to_vb(doppler_hz: np.ndarray, fc: float) -> np.ndarray:
    """v_b = -lambda f_d (m/s) of Doppler shifts in Hz."""
    return -wavelength(fc) * np.asarray(doppler_hz, dtype=float)


def sigmas(snr_db: np.ndarray | None, n: int, fc: float, fs: float, p: IngestParams
           ) -> tuple[np.ndarray, np.ndarray]:
    """(srb, svb) of n plots by the module docstring's formula (SNR in dB, or None)."""
    scale = np.ones(n) if snr_db is None else np.maximum(
        p.floor, 10.0 ** (-(np.asarray(snr_db, dtype=float) - p.snr_ref) / 20.0))
    q = 1.0 / np.sqrt(12.0)
    srb = np.full(n, p.srb) if p.srb > 0 else (C / fs) * q * scale
    svb = np.full(n, p.svb) if p.svb > 0 else (wavelength(fc) / p.cpi) * q * scale
    return srb, svb

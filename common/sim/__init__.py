"""The scenario simulator with ground truth: radar plots per channel (001 measurement
model), sonar detections (000 bearing and amplitude model), and the truth itself.

May import: ``common.core``, ``common.radar``, ``common.sonar``, ``common.deploy``.
Pure: deterministic for a seed, no clocks.
"""

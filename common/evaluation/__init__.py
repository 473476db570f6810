"""Scoring tracks against the simulator's truth: GOSPA/OSPA, number switches and
breaks, NEES, the posterior Cramer-Rao bound, crossing-swap evaluation (seed 004).

May import: ``common.core``, ``common.radar``, ``common.sonar``. Pure.
"""

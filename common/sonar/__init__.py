"""Passive sonar: the bearing tracker of seed 000 (Kalman filter, gating, GNN,
log-likelihood track quality), bearings-only TMA (seed 002) and constrained TMA with
wrong-bound handling (seed 003).

May import: ``common.core``. Pure: no I/O, no clocks, driven by message time.
"""

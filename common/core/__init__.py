"""The tracking core shared by every tracker: Kalman steps, motion models, gating,
assignment, IMM, track tables and crossing management (seed 004; Kalman/IMM textbook
steps named where 000 and 001 use them).

May import: numpy, scipy, filterpy only. Never radar, sonar, sim, wire, bus or Zenoh.
"""

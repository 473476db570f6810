"""Multistatic passive radar (seed 001): bistatic geometry [1]-[3], channel plot fusion
(modules 31-34), elementary tracking in bistatic coordinates (modules 41-44), and global
fusion (modules 61-65: ellipse-intersection initialisation, association, EKF).

May import: ``common.core``. Pure: no I/O, no clocks, driven by message time.
"""

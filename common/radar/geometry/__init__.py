"""Bistatic geometry of seed 001 ([1]-[3], [47]) and the localisation of a target from
bistatic measurements (module 64). Pure: numpy over arrays, no I/O."""

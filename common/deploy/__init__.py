"""The deployment file: its schema and parser (``config``), the parameter tables of
every service (``sections``), and which process runs where (``deployment``).

May import: ``common.core``, ``common.radar``, ``common.sonar`` (for their parameter
classes). No Zenoh.
"""

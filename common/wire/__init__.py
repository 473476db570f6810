"""What goes on the wire: the msgpack codec and validation of every message
(``protocol``, documented in docs/protocol.md) and the radar chain on message dicts
(``radar_chain``), which the radar services use to build their messages.

May import: ``common.core``, ``common.radar``, ``common.sonar``, ``common.deploy``. No Zenoh.
"""

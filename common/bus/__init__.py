"""Transport and service plumbing: Zenoh sessions, stamped publishers and bounded
inboxes (``transport``), the thin service runtime (``service``), recording, and the
child-process helpers (``procs``, and ``launcher``: commands forked from a fork server
that imported them once). The only package that talks to Zenoh.

May import: every package of ``common`` except ``cli``; never ``services``.
"""

RESTART = 75  # a service's exit code after a reset command: common.cli runs its main again

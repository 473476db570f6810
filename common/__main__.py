"""``python -m common ARGS`` is ``pfusion ARGS`` (what tests and supervisors start).

A ``-m`` entry named ``__main__`` is one that multiprocessing does not run again in the
fork server's children (``python -m common.cli`` was: a RuntimeWarning per child)."""

import sys

from common.cli import main

sys.exit(main())

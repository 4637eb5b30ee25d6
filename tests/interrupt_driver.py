"""``substruct`` started as its console script starts it, with a pause while one module is
imported, for the Ctrl-C tests of the command's start.

Usage: ``python tests/interrupt_driver.py MODULE substruct-arguments...``.  The first import
of ``MODULE`` prints ``PAUSED <MODULE> <pid>`` on stderr and sleeps first (60 s, or the
seconds in the environment variable ``PAUSE_SECONDS``) (a Ctrl-C
there raises ``KeyboardInterrupt`` inside that import, as it does in a slow import).  Then
``from substruct.cli import main; sys.exit(main())``, as the installed ``substruct`` does.
"""

import builtins
import os
import sys
import time

MODULE = sys.argv[1]
real_import = builtins.__import__
paused = []


def slow_import(name, *args, **kwargs):
    if name == MODULE and not paused:
        paused.append(name)
        sys.stderr.write(f"PAUSED {MODULE} {os.getpid()}\n")
        sys.stderr.flush()
        time.sleep(float(os.environ.get("PAUSE_SECONDS", "60")))
    return real_import(name, *args, **kwargs)


builtins.__import__ = slow_import
sys.argv = ["substruct", *sys.argv[2:]]

from substruct.cli import main  # noqa: E402

sys.exit(main())

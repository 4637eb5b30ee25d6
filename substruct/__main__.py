"""``python -m substruct``: the ``substruct`` command, as ``python -m substruct.cli``."""

import sys

from substruct.cli.main import main

__all__: list[str] = []

if __name__ == "__main__":  # pragma: no branch
    sys.exit(main())

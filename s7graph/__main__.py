"""``python -m s7graph …``: the same command line as the ``s7graph`` console script."""

from __future__ import annotations

import sys

from s7graph.web.cli import main

if __name__ == "__main__":
    sys.exit(main())

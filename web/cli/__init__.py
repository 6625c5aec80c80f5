"""The ``s7graph`` command line: :func:`main`; the commands are in ``web/cli/root.py``, each
command's work in a module of its own here.

``s7graph run`` started as the program becomes the supervisor of a CPU process of its own
(``web/cli/supervisor.py``) before typer, the commands and the engine are imported: the
CPU's process imports them, the supervisor stays small, and the CPU starts sooner.
"""

from __future__ import annotations

import signal
import sys

__all__ = ["main"]


def main(argv: list[str] | None = None) -> int:
    """Entry point of the console script; turns every known error into one stderr line
    (``root.main``). Run as the program (``argv`` None), ``s7graph run`` supervises its CPU
    as a process of its own; called with ``argv`` it runs in this process. The program's
    command done, Ctrl-C and SIGTERM are ignored while the process ends: one pressed again
    could only turn a clean end into a traceback or a killed process."""
    try:
        return _main(argv)
    finally:
        if argv is None:
            for sig in (signal.SIGINT, signal.SIGTERM):
                signal.signal(sig, signal.SIG_IGN)


def _main(argv: list[str] | None) -> int:
    if argv is None and sys.argv[1:2] == ["run"]:
        from s7graph.web.cli.supervisor import supervise, supervises

        if supervises(as_program=True):
            try:
                return supervise(sys.argv[1:])
            except OSError as exc:  # no shared page, no process: say so, as root.main would
                print(f"s7graph: error: cannot start the CPU's process: {exc}", file=sys.stderr)
                return 2
    from s7graph.web.cli.root import main as commands

    return commands(argv)

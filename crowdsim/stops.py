"""Clean stops: SIGTERM and SIGINT become one exception in the main process, so that every ``finally`` and
``except BaseException`` on the way out runs (a partial output folder is removed, worker processes are ended), the
command prints one line saying what was kept, and the process then ends by the same signal, as its caller expects.
Worker processes ignore both: the main process alone decides what to keep and ends them."""

from __future__ import annotations

import os
import signal
from contextlib import contextmanager

SIGNALS = (signal.SIGTERM, signal.SIGINT)


class Stopped(KeyboardInterrupt):
    """A stop asked for by a signal (a KeyboardInterrupt, so code that lets Ctrl-C through lets this through)."""

    def __init__(self, signum: int):
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


def _raise_stopped(signum, frame) -> None:
    for s in SIGNALS:  # a second signal must not cut the clean-up short
        signal.signal(s, signal.SIG_IGN)
    raise Stopped(signum)


@contextmanager
def stops_as_exceptions():
    """Within the block, SIGTERM and SIGINT raise ``Stopped``; the handlers before it come back after."""
    before = {s: signal.signal(s, _raise_stopped) for s in SIGNALS}
    try:
        yield
    finally:
        for s, handler in before.items():
            signal.signal(s, handler)


def end_by(signum: int) -> None:
    """End this process by ``signum`` with its default action, so the caller sees the signal's status."""
    signal.signal(signum, signal.SIG_DFL)
    os.kill(os.getpid(), signum)


def ignore_stops() -> None:
    """A worker process's initializer: the main process handles stops and ends its workers."""
    for s in SIGNALS:
        signal.signal(s, signal.SIG_IGN)

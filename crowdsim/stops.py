"""Clean stops: SIGTERM and SIGINT become one exception in the main process, so that every ``finally`` and
``except BaseException`` on the way out runs (a partial output folder is removed, worker processes are ended), the
command prints one line saying what was kept, and the process exits with the status a shell gives a process ended
by that signal (128 + its number: 143, 130). It exits rather than kills itself, so that the interpreter's own
clean-up runs too (multiprocessing's semaphores, which a process killed by a signal leaves to its resource tracker to
complain about). Worker processes ignore both: the main process alone decides what to keep and ends them.

Python runs a signal's handler between two bytecodes of the main thread, wherever it is. Where that is a finalizer
(``__del__``, a weakref callback: the garbage collector's work), the exception cannot leave it: Python prints
"Exception ignored in ..." and goes on, and the stop would be lost (the command ran to its end with status 0). A
stop swallowed so is raised again a moment later (SIGALRM, ``RETRY_S``) from wherever the main thread is then."""

from __future__ import annotations

import signal
import sys
from contextlib import contextmanager

SIGNALS = (signal.SIGTERM, signal.SIGINT)
RETRY_S = 0.001  # s after a swallowed stop that it is raised again (out of the finalizer by then)


class Stopped(KeyboardInterrupt):
    """A stop asked for by a signal (a KeyboardInterrupt, so code that lets Ctrl-C through lets this through)."""

    def __init__(self, signum: int):
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


def _raise_stopped(signum, frame) -> None:
    for s in SIGNALS:  # a second signal must not cut the clean-up short
        signal.signal(s, signal.SIG_IGN)
    _stop(signum)


def _stop(signum: int) -> None:
    lock = getattr(sys.modules.get("numba.core.compiler_lock"), "global_compiler_lock", None)
    if lock is not None and lock.is_locked():
        _raise_when_unlocked(lock, signum)
        return
    raise Stopped(signum)


def _raise_when_unlocked(lock, signum: int) -> None:
    """Raise ``Stopped`` once numba lets its compiler lock go. Why: a stop raised while numba compiles or loads a
    kernel leaves that kernel's library half made, and the clean-up's next call of it fails ("no compiled object
    yet") where the stop should have been reported; the compile or load is done within moments."""
    from numba.core import event

    class Unlocked(event.Listener):
        def on_start(self, e) -> None:
            pass

        def on_end(self, e) -> None:
            if not lock.is_locked():  # the outermost hold let go: the kernel is whole
                event.unregister("numba:compiler_lock", self)
                raise Stopped(signum)

    event.register("numba:compiler_lock", Unlocked())


@contextmanager
def stops_as_exceptions():
    """Within the block, SIGTERM and SIGINT raise ``Stopped`` (again, where a finalizer swallowed it); the handlers
    and ``sys.unraisablehook`` before it come back after."""
    before = {s: signal.signal(s, _raise_stopped) for s in SIGNALS}
    hook, alarm = sys.unraisablehook, []  # alarm: SIGALRM's handler before, once a retry has taken it

    def swallowed(unraisable) -> None:
        if not isinstance(unraisable.exc_value, Stopped):
            hook(unraisable)
            return
        signum = unraisable.exc_value.signum
        previous = signal.signal(signal.SIGALRM, lambda *_: _stop(signum))
        alarm[:] = alarm or [previous]
        signal.setitimer(signal.ITIMER_REAL, RETRY_S)

    sys.unraisablehook = swallowed
    try:
        yield
    finally:
        sys.unraisablehook = hook
        if alarm:
            signal.setitimer(signal.ITIMER_REAL, 0.0)
            signal.signal(signal.SIGALRM, alarm[0])
        for s, handler in before.items():
            signal.signal(s, handler)


@contextmanager
def stops_held():
    """SIGINT and SIGTERM held back within the block (workers being ended, a folder being tidied), so that a second
    Ctrl-C cannot leave the work half done; one that came meanwhile is dropped (the first is being handled)."""
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, set(SIGNALS))
    try:
        yield
    finally:
        try:
            signal.pthread_sigmask(signal.SIG_SETMASK, old)
        except KeyboardInterrupt:  # the held Ctrl-C, delivered as the mask lifts
            pass


def ignore_stops() -> None:
    """A worker process's initializer: the main process handles stops and ends its workers."""
    for s in SIGNALS:
        signal.signal(s, signal.SIG_IGN)

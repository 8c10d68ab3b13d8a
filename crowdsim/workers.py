"""Local worker processes for the many-run commands: spawned (a fresh interpreter each: MuJoCo's and the BLAS's
threads are not forked), deaf to stops (crowdsim/stops.py), and ended at once when the main process stops or fails,
rather than waited for."""

from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager
from multiprocessing import get_context

from .stops import ignore_stops, stops_held


def _start(initializer, initargs) -> None:
    ignore_stops()
    if initializer is not None:
        initializer(*initargs)


@contextmanager
def process_pool(workers: int, initializer=None, initargs: tuple = ()):
    """A ``ProcessPoolExecutor`` of ``workers`` spawned processes, each first running ``initializer(*initargs)``.
    Leaving the block by an exception (a stop, a failure) cancels what is queued and ends the workers."""
    pool = ProcessPoolExecutor(workers, mp_context=get_context("spawn"), initializer=_start,
                               initargs=(initializer, initargs))
    try:
        yield pool
    except BaseException:
        with stops_held():
            processes = list((pool._processes or {}).values())  # no public handle on the workers before 3.14
            for process in processes:
                process.kill()  # they ignore SIGTERM (ignore_stops), and what they were doing is not to be finished
            pool.shutdown(wait=False, cancel_futures=True)
            for process in processes:
                process.join()
        raise
    pool.shutdown()

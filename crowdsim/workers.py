"""Where the many-run commands run their runs: in the calling process, in local worker processes (``--workers K``),
or as Ray tasks on a cluster or a local one (``--ray [ADDRESS]``). The results come back in the order of the runs
whatever the engine and the number of workers, so the tables do not depend on them.

Local workers are spawned (a fresh interpreter each: MuJoCo's and the BLAS's threads are not forked), deaf to stops
(crowdsim/stops.py), and ended at once when the main process stops or fails, rather than waited for; unfinished Ray
tasks are cancelled then.
"""

from __future__ import annotations

import os
import signal
import threading
from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager
from functools import partial
from multiprocessing import get_context
from typing import NamedTuple

from tqdm import tqdm

from .errors import Error
from .stops import ignore_stops, stops_held


class Engine(NamedTuple):
    """``workers`` processes, or Ray tasks at ``ray`` ("local": a Ray of this machine with that many CPUs)."""

    workers: int = 1
    ray: str | None = None


class WorkersError(Error):
    """--workers or --ray cannot be used as given."""


def add_arguments(parser, workers: int = 2) -> None:
    """The flags of a many-run command: --workers and --ray."""
    parser.add_argument("--workers", type=int, default=workers,
                        help=f"processes running the runs (default {workers}); with --ray, the local Ray's CPUs")
    parser.add_argument("--ray", nargs="?", const="local", metavar="ADDRESS",
                        help="run the runs as Ray tasks: on the cluster at ADDRESS, or a local one (needs [ray])")


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


@contextmanager
def ray_session(address: str, workers: int):
    """Ray, connected to the cluster at ``address`` or started on this machine ("local", ``workers`` CPUs) unless
    it already runs; a Ray started here is shut down at the end, and the command keeps its own stop handlers."""
    try:
        import ray
    except ImportError:
        raise WorkersError("--ray: Ray is not installed; expected pip install -e \".[ray]\"") from None
    started = not ray.is_initialized()
    if started:
        handlers = {}
        if threading.current_thread() is threading.main_thread():
            handlers = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
        ray.init(address=None if address == "local" else address, num_cpus=workers if address == "local" else None,
                 runtime_env={"env_vars": {"MUJOCO_GL": os.environ.get("MUJOCO_GL", "")}}, include_dashboard=False,
                 log_to_driver=False)
        for s, handler in handlers.items():  # a local head node takes SIGTERM for itself: the command's stops go on
            if handler is not None:
                signal.signal(s, handler)
    try:
        yield ray
    finally:
        if started:
            ray.shutdown()


def ray_results(ray, refs: list):
    """The results of the Ray tasks ``refs`` as each ends (with its index); on an error or an interruption the
    tasks not finished are cancelled (their workers killed)."""
    index = {ref: k for k, ref in enumerate(refs)}
    pending = list(refs)
    try:
        while pending:
            finished, pending = ray.wait(pending, num_returns=1, timeout=0.5)
            for ref in finished:
                yield index[ref], ray.get(ref)
    except BaseException:
        with stops_held():
            for ref in pending:
                try:
                    ray.cancel(ref, force=True)
                except Exception:  # noqa: BLE001 - finished meanwhile, or the cluster gone
                    pass
        raise


def _call(fn, *args):
    return fn(*args)


def run_all(fn, items: list, *args, engine: Engine = Engine(), desc: str = "runs", unit: str = "run",
            progress: bool = True) -> list:
    """``[fn(item, *args) for item in items]``, in that order, on ``engine``, with a progress bar; ``fn`` must be
    importable (a module's function) for worker processes and Ray."""
    with runner(engine) as run:
        return run(fn, items, *args, desc=desc, unit=unit, progress=progress)


@contextmanager
def runner(engine: Engine = Engine()):
    """``run_all`` for many calls on one engine: the worker processes (or the Ray session) start once for the
    block, not once a call (a study of many small batches would otherwise pay the start-up each time)."""
    if engine.ray is not None:
        with ray_session(engine.ray, engine.workers) as ray:
            task = ray.remote(num_cpus=1)(_call)  # (a Ray task is a Python function; fn may be a builtin)

            def results(fn, items, args):
                shared = [ray.put(a) for a in args]
                return ray_results(ray, [task.remote(fn, item, *shared) for item in items])

            yield partial(_run, results)
    elif engine.workers <= 1:
        yield partial(_run, lambda fn, items, args: ((k, fn(item, *args)) for k, item in enumerate(items)))
    else:
        with process_pool(engine.workers) as pool:
            yield partial(_run, lambda fn, items, args: enumerate(
                pool.map(fn, items, *([a] * len(items) for a in args))))


def _run(results, fn, items: list, *args, desc: str = "runs", unit: str = "run", progress: bool = True) -> list:
    """The results of ``fn`` over ``items`` from ``results`` ((index, result) pairs in any order), in order."""
    out = [None] * len(items)
    with tqdm(total=len(items), unit=unit, desc=desc, disable=not progress) as bar:
        for k, result in results(fn, items, args):
            out[k] = result
            bar.update()
    return out

"""Where the many-run commands run their runs (crowdsim/workers.py): the results in the order of the runs, in this
process, in worker processes and as Ray tasks (``crowdsim navigate``'s table on each engine: test_navigation_loop)."""

import operator
import os

from crowdsim.workers import Engine, run_all, runner


def test_runs_come_back_in_their_order_on_every_engine():
    # pow(item, 3) of 0..9: 0, 1, 8, ..., 729, whichever worker ends first
    expected = [k ** 3 for k in range(10)]
    for engine in (Engine(), Engine(2), Engine(2, "local")):
        assert run_all(operator.pow, list(range(10)), 3, engine=engine, progress=False) == expected


def _pid(item) -> int:
    return os.getpid()


def test_a_runner_keeps_its_two_workers_for_every_call():
    with runner(Engine(2)) as run:
        assert run(operator.pow, [2, 3], 2, progress=False) == [4, 9]
        pids = {pid for _ in range(3) for pid in run(_pid, list(range(6)), progress=False)}
    assert len(pids) <= 2 and os.getpid() not in pids  # 18 runs over three calls, on the same two processes

"""Where the many-run commands run their runs (crowdsim/workers.py): the results in the order of the runs, in this
process, in worker processes and as Ray tasks (``crowdsim navigate``'s table on each engine: test_navigation_loop)."""

import operator

from crowdsim.workers import Engine, run_all


def test_runs_come_back_in_their_order_on_every_engine():
    # pow(item, 3) of 0..9: 0, 1, 8, ..., 729, whichever worker ends first
    expected = [k ** 3 for k in range(10)]
    for engine in (Engine(), Engine(2), Engine(2, "local")):
        assert run_all(operator.pow, list(range(10)), 3, engine=engine, progress=False) == expected


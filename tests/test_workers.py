"""Where the many-run commands run their runs (crowdsim/workers.py): the same results, in the order of the runs, in
this process, in worker processes and as Ray tasks, for a hand-checkable function and for Table II's experiment."""

import operator

import numpy as np

from crowdsim.experiments.table2 import COLUMNS, table2
from crowdsim.workers import Engine, run_all

HZ = COLUMNS.index("hz")  # the tracker's cycles per second: a timing, the one figure that is the machine's


def test_runs_come_back_in_their_order_on_every_engine():
    # pow(item, 3) of 0..9: 0, 1, 8, ..., 729, whichever worker ends first
    expected = [k ** 3 for k in range(10)]
    for engine in (Engine(), Engine(2), Engine(2, "local")):
        assert run_all(operator.pow, list(range(10)), 3, engine=engine, progress=False) == expected


def test_table2_is_the_same_on_one_process_two_and_ray():
    seeds = [1, 2]
    tables = [table2(seeds, duration=1.0, engine=engine, progress=False)
              for engine in (Engine(), Engine(2), Engine(2, "local"))]
    for name in tables[0]:
        first = np.delete(tables[0][name], HZ, axis=2)
        for other in tables[1:]:
            np.testing.assert_array_equal(np.delete(other[name], HZ, axis=2), first)

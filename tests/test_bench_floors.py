"""``crowdsim bench floors``: the parts timed inside a figure's own run, and the ceiling they put on it (the
mechanism and the arithmetic; the figures themselves are the machine's, so no test asserts a time)."""

import time
import types

import pytest

from crowdsim.bench import floors


def _busy(seconds: float) -> None:
    end = time.process_time() + seconds
    while time.process_time() < end:
        pass


def test_a_wrapped_function_is_timed_from_the_start_and_given_back_after():
    module = types.SimpleNamespace(work=_busy, other=lambda: None)
    spent = floors.Spent()
    with spent.wrapping(module, "work"):
        assert module.work is not _busy
        module.work(0.02)  # before the window: not counted
        spent.start()
        module.work(0.05)
        module.work(0.05)
        module.other()
        window = spent.window()
    assert module.work is _busy  # the original is back
    assert spent.calls == {"work": 2}
    assert 0.1 <= spent.seconds["work"] <= window


def test_a_wrapped_method_is_timed_on_every_instance():
    class Sensor:
        def scan(self, seconds):
            _busy(seconds)
            return self

    spent = floors.Spent()
    with spent.wrapping(Sensor, "scan"):
        spent.start()
        a, b = Sensor(), Sensor()
        assert a.scan(0.01) is a and b.scan(0.01) is b
    assert spent.calls == {"scan": 2} and spent.seconds["scan"] >= 0.02
    assert Sensor.scan.__name__ == "scan"


def test_the_ceiling_is_the_rate_over_the_floors_share():
    # 2 sim s per CPU s over a window of 5 CPU s, of which 2 s are the floor: at best 2 / (2 / 5) = 5
    assert floors.ceiling(2.0, 2.0, 5.0) == pytest.approx(5.0)
    f = floors._figure("x", 2.0, 5.0, {"a": {"cpu_s": 1.5, "calls": 3}, "b": {"cpu_s": 0.5, "calls": 1},
                                       "c": {"cpu_s": 2.0, "calls": 7}}, ["a", "b"], 4.0, "a and b")
    assert f["floor_share"] == pytest.approx(0.4) and f["ceiling"] == pytest.approx(5.0)
    assert f["parts"]["c"] == {"cpu_s": 2.0, "calls": 7, "share": pytest.approx(0.4), "in_floor": False}


def test_the_vector_envs_ticks_are_timed_once_a_step_of_the_timed_window():
    f = floors.vector_truth(quick=True)
    ticks = f["parts"]["_people_ticks"]
    assert ticks["calls"] == 40  # the quick figure's timed steps, not its 100 untimed ones
    assert 0.0 < ticks["share"] < 1.0 and ticks["in_floor"]
    assert f["ceiling"] == pytest.approx(f["measured"] / ticks["share"])
    from crowdsim.envs import world
    assert world._people_ticks.__module__ == "crowdsim.envs.world"  # given back: the kernel itself again
    assert hasattr(world._people_ticks, "py_func")

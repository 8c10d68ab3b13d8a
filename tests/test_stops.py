"""Clean stops of a real process: SIGTERM or SIGINT halfway through a run removes the partial folder, prints one
line saying what was kept (no traceback), and the process exits with the signal's status (128 + its number)."""

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest


def start_and_stop(args: list[str], cwd: Path, signum: int, ready) -> tuple[int, str]:
    """Start ``crowdsim ARGS`` in ``cwd``, wait until ``ready()`` holds (the work is under way), send ``signum``."""
    p = subprocess.Popen([sys.executable, "-m", "crowdsim.cli", *args], cwd=cwd, stdout=subprocess.DEVNULL,
                         stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while not ready() and time.monotonic() < deadline and p.poll() is None:
            time.sleep(0.1)
        assert p.poll() is None, p.stderr.read()
        time.sleep(1.0)  # into the loop itself
        p.send_signal(signum)
        _, err = p.communicate(timeout=60)
    finally:
        p.kill()
    return p.returncode, err


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT])
def test_a_run_stopped_halfway_leaves_nothing(tmp_path, signum):
    def partial():
        return any(".crowdsim-partial-" in p.name for p in tmp_path.iterdir())

    rc, err = start_and_stop(["run", "airport_disembarkation", "--duration", "600", "--quiet", "--out", "run"],
                             tmp_path, signum, partial)
    assert rc == 128 + signum
    name = signal.Signals(signum).name
    assert err.strip().splitlines() == [f"crowdsim: stopped by {name}; nothing was kept: run was not written"]
    assert list(tmp_path.iterdir()) == []


def test_a_stop_while_numba_compiles_comes_when_the_kernel_is_made():
    """A signal while numba holds its compiler lock (compiling or loading a kernel) is raised only once the
    outermost hold lets go, so no kernel is left half made; outside the lock it is raised at once."""
    from numba.core.compiler_lock import global_compiler_lock

    from crowdsim.stops import Stopped, _raise_stopped, stops_as_exceptions

    reached_after_inner = False
    with stops_as_exceptions():
        with pytest.raises(Stopped) as stop:
            with global_compiler_lock:
                with global_compiler_lock:  # a kernel compiled while another compiles
                    _raise_stopped(signal.SIGTERM, None)
                reached_after_inner = True  # the inner release raised nothing
            pytest.fail("the stop was not raised when the lock was let go")
    assert reached_after_inner and stop.value.signum == signal.SIGTERM and not global_compiler_lock.is_locked()
    with stops_as_exceptions():
        with pytest.raises(Stopped):
            _raise_stopped(signal.SIGINT, None)


def test_a_stop_that_lands_in_a_finalizer_is_raised_again_outside_it(capfd):
    """A signal whose handler runs inside a finalizer (``__del__``, a weakref callback) cannot raise there: Python
    prints "Exception ignored" and goes on. Stop 41's and 42's flake: generate then ran to its end with status 0.
    The stop comes again a moment later, where the main thread is then, and nothing is printed."""
    import time

    from crowdsim.stops import Stopped, stops_as_exceptions

    class Dropped:
        def __del__(self):
            signal.raise_signal(signal.SIGTERM)  # its handler runs here, inside the finalizer
            self.after = True  # a bytecode boundary after the signal

    with stops_as_exceptions():
        with pytest.raises(Stopped) as stop:
            Dropped()  # finalized at once
            reached = True  # the finalizer swallowed the first raise
            deadline = time.monotonic() + 5.0
            while time.monotonic() < deadline:
                pass
            pytest.fail("the swallowed stop was not raised again")
    assert reached and stop.value.signum == signal.SIGTERM
    assert "Exception ignored" not in capfd.readouterr().err
    assert signal.getsignal(signal.SIGALRM) == signal.SIG_DFL and signal.getitimer(signal.ITIMER_REAL) == (0.0, 0.0)
    assert signal.getsignal(signal.SIGTERM) != signal.SIG_IGN  # the handlers before came back

"""``crowdsim bench floors``: for the speed figures whose targets (``crowdsim bench speed``'s) are not met, the work
each cannot shed while its sensors stay MuJoCo's and its crowd keeps its force model, timed inside the figure's own
run, and the figure that work alone would allow.

* the cameras loop: MuJoCo's GL calls (``mjv_updateScene``, ``mjr_render``, ``mjr_readPixels``: under Mesa the
  drawing itself, in CPU time of every thread of the process, the renderer's included), plus the airport loop it
  runs besides (the same scenario without cameras, timed over as many simulated seconds: the loop figure);
* the vector env with ``truth``: the crowd's ticks (``crowdsim.envs.world._people_ticks``, one compiled call a step:
  the pair, wall and robot forces, the integration and the contacts of every world);
* the vector env with ``tracks``: each world's laser, its scene's sync (``Scene.sync``) and ``mj_multiRay``; the
  robot software (``RobotSoftware.receive`` and ``cycle``) is shown beside it, not counted in the floor.

A figure can reach at most its measured value over the share of its CPU its floor takes (were everything else
free): the ceiling printed beside the target. The parts are timed by wrapping them for the run (``Spent``).
"""

from __future__ import annotations

import time
from contextlib import contextmanager

from .common import add_arguments  # noqa: F401  (its flags: those every benchmark takes)
from .common import write_figures
from . import probe


class Spent:
    """CPU seconds spent in the wrapped callables since ``start`` (and in the whole window)."""

    def __init__(self):
        self.seconds: dict[str, float] = {}
        self.calls: dict[str, int] = {}
        self.started = None

    def start(self) -> None:
        self.seconds = dict.fromkeys(self.seconds, 0.0)
        self.calls = dict.fromkeys(self.calls, 0)
        self.started = time.process_time()

    def window(self) -> float:
        """CPU seconds since ``start``."""
        return time.process_time() - self.started

    @contextmanager
    def wrapping(self, owner, *names: str):
        """``owner``'s attributes ``names`` (functions of a module, or methods of a class) timed while inside."""
        originals = {name: getattr(owner, name) for name in names}
        for name, fn in originals.items():
            self.seconds[name], self.calls[name] = 0.0, 0
            setattr(owner, name, self._timed(name, fn))
        try:
            yield self
        finally:
            for name, fn in originals.items():
                setattr(owner, name, fn)

    def parts(self) -> dict:
        """{name: {cpu_s, calls}} of every wrapped callable."""
        return {name: {"cpu_s": s, "calls": self.calls[name]} for name, s in self.seconds.items()}

    def _timed(self, name: str, fn):
        def timed(*args, **kwargs):
            t = time.process_time()
            try:
                return fn(*args, **kwargs)
            finally:
                self.seconds[name] += time.process_time() - t
                self.calls[name] += 1
        return timed


def ceiling(rate: float, floor_s: float, window_s: float) -> float:
    """The most a figure measured at ``rate`` can reach when ``floor_s`` of its ``window_s`` CPU seconds stay."""
    return rate * window_s / floor_s


def cameras(quick: bool) -> dict:
    import mujoco

    duration = 2.0 if quick else 10.0
    spent = Spent()
    with spent.wrapping(mujoco, "mjv_updateScene", "mjr_render", "mjr_readPixels"):
        rate = probe.loop("airport_disembarkation_cameras", duration, timing=spent.start)
        window = spent.window()
    parts = spent.parts()
    parts["airport loop"] = {"cpu_s": duration / probe.loop("airport_disembarkation", duration)["sim_s_per_cpu_s"],
                             "calls": 1}
    return _figure("cameras loop, sim s / CPU s", rate["sim_s_per_cpu_s"], window, parts, list(parts), 4.0,
                   "GL calls + the airport loop")


def vector_truth(quick: bool) -> dict:
    from crowdsim.envs import world

    spent = Spent()
    with spent.wrapping(world, "_people_ticks"):
        rate = probe.env("truth", 64, 10, 40 if quick else 400, untimed=100, timing=spent.start)
        window = spent.window()
    return _figure("vector 64 x 10 truth, env-steps / CPU s", rate["env_steps_per_cpu_s"], window, spent.parts(),
                   ["_people_ticks"], 40_000.0, "the crowd's ticks")


def vector_tracks(quick: bool) -> dict:
    import mujoco

    from pipeline.software import RobotSoftware
    from sensors.scene import Scene

    spent = Spent()
    with spent.wrapping(mujoco, "mj_multiRay"), spent.wrapping(Scene, "sync"), \
            spent.wrapping(RobotSoftware, "receive", "cycle"):
        rate = probe.env("tracks", 64, 10, 3 if quick else 20, timing=spent.start)
        window = spent.window()
    return _figure("vector 64 x 10 tracks, env-steps / CPU s", rate["env_steps_per_cpu_s"], window, spent.parts(),
                   ["sync", "mj_multiRay"], 8_000.0, "each world's scene sync and laser cast")


def _figure(what: str, rate: float, window: float, parts: dict, floor: list[str], target: float,
            floor_what: str) -> dict:
    """One figure's row: its ``parts`` ({name: {cpu_s, calls}}) with their shares of the ``window``, and the ceiling
    its ``floor`` parts put on it."""
    floor_s = sum(parts[name]["cpu_s"] for name in floor)
    return {"figure": what, "measured": rate, "target": target, "floor": floor_what, "floor_share": floor_s / window,
            "ceiling": ceiling(rate, floor_s, window), "window_cpu_s": window,
            "parts": {name: {**p, "share": p["cpu_s"] / window, "in_floor": name in floor} for name, p in parts.items()}}


FLOORS = {"cameras": cameras, "vector_truth": vector_truth, "vector_tracks": vector_tracks}


def main(args) -> int:
    """``crowdsim bench floors``."""
    from ..cli import check_json

    check_json(args)
    figures = {}
    print(f"{'figure':42s}{'measured':>10s}{'floor':>44s}{'share':>7s}{'ceiling':>10s}{'target':>9s}")
    for name, measure in FLOORS.items():
        f = figures[name] = measure(args.quick)
        print(f"{f['figure']:42s}{f['measured']:10,.2f}{f['floor']:>44s}{f['floor_share']:7.0%}{f['ceiling']:10,.2f}"
              f"{f['target']:9,.0f}", flush=True)
        for part, p in f["parts"].items():
            print(f"{'':52s}{part:>30s}: {p['cpu_s']:7.3f} CPU s, {p['share']:4.0%}, {p['calls']:,} calls"
                  f"{'' if p['in_floor'] else ' (not in the floor)'}")
    write_figures(args.json, figures)
    return 0

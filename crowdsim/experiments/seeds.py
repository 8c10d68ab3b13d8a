"""One function of a seed over many seeds, in order, with a progress bar, on the engine the command was given
(crowdsim/workers.py: this process, local worker processes, or Ray)."""

from __future__ import annotations

from ..workers import Engine, run_all


def map_seeds(fn, seeds: list[int], *args, engine: Engine = Engine(), desc: str = "seeds",
              progress: bool = True) -> list:
    """``[fn(seed, *args) for seed in seeds]``; ``fn`` must be importable (a module's function) for worker processes
    and Ray."""
    return run_all(fn, seeds, *args, engine=engine, desc=desc, unit="seed", progress=progress)

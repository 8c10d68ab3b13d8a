"""One function of a seed over many seeds, in order, with a progress bar: in the calling process, or in ``workers``
worker processes (crowdsim/workers.py)."""

from __future__ import annotations

from tqdm import tqdm

from ..workers import process_pool


def map_seeds(fn, seeds: list[int], *args, workers: int = 1, desc: str = "seeds", progress: bool = True) -> list:
    """``[fn(seed, *args) for seed in seeds]``; ``fn`` must be importable (a module's function) for ``workers`` > 1."""
    out = []
    with tqdm(total=len(seeds), unit="seed", desc=desc, disable=not progress) as bar:
        if workers <= 1:
            for seed in seeds:
                out.append(fn(seed, *args))
                bar.update()
            return out
        with process_pool(workers) as pool:
            for result in pool.map(fn, seeds, *([a] * len(seeds) for a in args)):
                out.append(result)
                bar.update()
    return out

"""One function of a seed over many seeds, in order, with a progress bar: in the calling process, or in ``workers``
spawned processes (each a fresh interpreter: MuJoCo's and the BLAS's threads are not forked)."""

from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context

from tqdm import tqdm


def map_seeds(fn, seeds: list[int], *args, workers: int = 1, desc: str = "seeds", progress: bool = True) -> list:
    """``[fn(seed, *args) for seed in seeds]``; ``fn`` must be importable (a module's function) for ``workers`` > 1."""
    out = []
    with tqdm(total=len(seeds), unit="seed", desc=desc, disable=not progress) as bar:
        if workers <= 1:
            for seed in seeds:
                out.append(fn(seed, *args))
                bar.update()
            return out
        with ProcessPoolExecutor(workers, mp_context=get_context("spawn")) as pool:
            for result in pool.map(fn, seeds, *([a] * len(seeds) for a in args)):
                out.append(result)
                bar.update()
    return out

"""``crowdsim bench dataset``: a dataset episode's generation speed per worker and its bytes per frame, with the two
lasers of ``airport_disembarkation`` and with the camera set of ``airport_disembarkation_cameras``, compressed as
the command writes by default and uncompressed.

The rate counts the recorded frames over the time from the first frame to the last: the warm-up (crowd only, no
sensors) is left out, as it is the same whatever is written. Each file's bytes per frame come from the episode's
files on disk.
"""

from __future__ import annotations

import platform
import tempfile
import time
from pathlib import Path

from scenarios import load_scenario
from scenarios.typed import Scenario

from ..datasets.episode import write_episode
from ..datasets.layout import EPISODE_FILES
from .common import write_figures
from .common import add_arguments  # noqa: F401  (its flags: those every benchmark takes)

SENSOR_SETS = {"two lasers": "airport_disembarkation", "two lasers, two RGB-D and two wall cameras":
               "airport_disembarkation_cameras"}


def measure(scenario: Scenario, duration: float, compression: str) -> dict:
    """Frames/s of writing one episode, and each file's bytes per frame."""
    with tempfile.TemporaryDirectory() as folder:
        stamps = []
        frames = write_episode(scenario, scenario.seed, duration, Path(folder), compression,
                               lambda stamp: stamps.append(time.perf_counter()))
        sizes = {name: (Path(folder) / name).stat().st_size / frames for name in EPISODE_FILES}
    return {"frames": frames, "frames_per_s": (len(stamps) - 1) / (stamps[-1] - stamps[0]),
            "bytes_per_frame": sizes, "total_bytes_per_frame": sum(sizes.values())}


def run_dataset_benchmark(json_path: str | None = None, quick: bool = False) -> dict:
    duration = 4.0 if quick else 20.0
    print(f"crowdsim bench dataset on {platform.processor() or platform.machine()}, Python "
          f"{platform.python_version()}: one episode of {duration:g} s per line, one worker")
    figures = {"duration_s": duration}
    for label, name in SENSOR_SETS.items():
        scenario = load_scenario(name)
        for compression in ("gzip", "none"):
            r = measure(scenario, duration, compression)
            figures[f"{name}/{compression}"] = r
            files = ", ".join(f"{n.split('.')[0]} {b / 1e3:,.1f}" for n, b in r["bytes_per_frame"].items())
            print(f"  {label:45s} {compression:5s} {r['frames_per_s']:6.1f} frames/s  "
                  f"{r['total_bytes_per_frame'] / 1e3:8.1f} kB/frame ({files})")
    write_figures(json_path, figures)
    return figures


def main(args) -> int:
    """``crowdsim bench dataset``."""
    from ..cli import check_json

    check_json(args)
    run_dataset_benchmark(json_path=args.json, quick=args.quick)
    return 0

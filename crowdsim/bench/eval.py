"""``crowdsim bench eval``: frames per second of the evaluation on 5000 frames of 80 persons: CLEAR-MOT with its
trajectory and identity measures (the issue's target: 5000 frames/s), HOTA, OSPA, all of them together on the
sequence in memory, and all of them as ``crowdsim evaluate`` runs them: streamed from CSV files, read twice.

The sequence is synthetic but shaped like a tracking run: 80 persons walk at 1.3 m/s for 5000 cycles at 25 Hz,
every tenth ground-truth row is occluded (ignored), the tracks follow at 0.1 m of noise and miss 10% of the rows,
a track is re-initialised on someone 1% of the frames, and there are a few false positives each frame. Each figure
is the median of three timed runs over the whole sequence.
"""

from __future__ import annotations

import platform
import tempfile
import time
from pathlib import Path

import numpy as np

from evaluation import Sequence

from .common import write_figures
from .common import add_arguments  # noqa: F401  (its flags: those every benchmark takes)

FRAMES, PERSONS = 5000, 80


def synthetic_run(frames: int = FRAMES, persons: int = PERSONS, seed: int = 0) -> tuple[Sequence, Sequence]:
    rng = np.random.default_rng(seed)
    pos = rng.uniform(0, 30, (persons, 2))
    heading = rng.uniform(-np.pi, np.pi, persons)
    track_of = np.arange(persons) + 1000
    gt, tracks = [], []
    for f in range(frames):
        heading += rng.normal(0, 0.05, persons)
        pos += 0.04 * 1.3 * np.stack([np.cos(heading), np.sin(heading)], 1)
        gt.append(np.column_stack([np.full(persons, f), np.arange(persons), pos, rng.random(persons) < 0.1]))
        if rng.random() < 0.01:
            track_of[rng.integers(persons)] = track_of.max() + 1
        seen = rng.random(persons) > 0.1
        noisy = pos[seen] + rng.normal(0, 0.1, (seen.sum(), 2))
        ghosts = rng.uniform(0, 30, (3, 2))
        tracks.append(np.column_stack([np.full(seen.sum() + 3, f), np.r_[track_of[seen], [-1, -2, -3]],
                                       np.r_[noisy, ghosts]]))
    g, t = np.concatenate(gt), np.concatenate(tracks)
    return (Sequence.from_rows(g[:, 0], g[:, 1], g[:, 2:4], ignore=g[:, 4] > 0),
            Sequence.from_rows(t[:, 0], t[:, 1], t[:, 2:4]))


def _frames_per_s(fn, frames: int, runs: int = 3) -> float:
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return frames / float(np.median(times))


def write_csvs(folder: Path, gt: Sequence, tracks: Sequence) -> tuple[Path, Path]:
    """The sequences in the layout ``crowdsim run`` writes (frame, t, id, x, y[, visible])."""
    paths = folder / "groundtruth.csv", folder / "tracks.csv"
    for path, seq, extra in ((paths[0], gt, ",visible"), (paths[1], tracks, "")):
        columns = [seq.frame, 0.04 * seq.frame, seq.id, seq.position[:, 0], seq.position[:, 1]]
        fmt = ["%d", "%.2f", "%d", "%.4f", "%.4f"]
        if extra:
            columns.append(~seq.ignore)
            fmt.append("%d")
        np.savetxt(path, np.column_stack(columns), fmt=fmt, delimiter=",", header="frame,t,id,x,y" + extra,
                   comments="")
    return paths


def run_eval_benchmark(json_path: str | None = None, quick: bool = False) -> dict:
    from evaluation.clearmot import evaluate
    from evaluation.hota import hota
    from evaluation.ospa import ospa
    from evaluation.score import score_tracking
    from evaluation.stream import CsvPair, SequencePair

    frames = 500 if quick else FRAMES
    gt, tracks = synthetic_run(frames)
    print(f"crowdsim bench eval on {platform.processor() or platform.machine()}, Python "
          f"{platform.python_version()}: {frames} frames of {PERSONS} persons{' (quick)' if quick else ''}")
    counted = gt.select(~gt.ignore)
    with tempfile.TemporaryDirectory() as folder:
        files = CsvPair(*write_csvs(Path(folder), gt, tracks))
        figures = {"frames": frames, "persons": PERSONS,
                   "clear_mot_frames_per_s": _frames_per_s(lambda: evaluate(gt, tracks, 1.0), frames),
                   "hota_frames_per_s": _frames_per_s(lambda: hota(counted, tracks), frames),
                   "ospa_frames_per_s": _frames_per_s(lambda: ospa(counted, tracks), frames),
                   "all_of_it_frames_per_s": _frames_per_s(
                       lambda: score_tracking(SequencePair(gt, tracks), 1.0), frames),
                   "from_csv_frames_per_s": _frames_per_s(lambda: score_tracking(files, 1.0), frames)}
    for label, key, target in (("CLEAR-MOT, MT/ML, fragmentations, id swaps, IDF1", "clear_mot", " (target 5000)"),
                               ("HOTA (19 alphas)", "hota", ""), ("OSPA and OSPA-T", "ospa", ""),
                               ("all of these together, in memory", "all_of_it", ""),
                               ("all of these from the CSV files (crowdsim evaluate)", "from_csv", "")):
        print(f"  {label:50s} {figures[key + '_frames_per_s']:9.0f} frames/s{target}")
    write_figures(json_path, figures)
    return figures


def main(args) -> int:
    """``crowdsim bench eval``."""
    from ..cli import check_json

    check_json(args)
    run_eval_benchmark(json_path=args.json, quick=args.quick)
    return 0

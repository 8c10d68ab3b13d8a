"""``crowdsim experiment seed001``: seed 001's Tables 2-6 (Mekonnen, Lerasle & Herbulot, Sec. 6) on our room, beside
the published values, and its claims checked one by one.

Each sequence (``seed001_room_1/2/3``: 2, 3 and 4 passers-by, 200, 200 and 186 frames at 5 Hz) is simulated once at its
scenario's seed, with every detector of seed 001's system running (the leg detector with its raw blobs, each wall
camera's foreground blobs and HOG windows); the RJMCMC filter then runs on the recording in each of the paper's four
modes (the detector weights k_d of Sec. 6), ``runs`` times with different filter seeds, as seed 001 ran each sequence
eight times "to account for the stochastic nature of the filter". The cameras' background model learns from the
``LEAD_IN`` seconds before a sequence (15 frames; a wall camera's model would be long settled); the filter starts with
the sequence.

Scoring is seed 001's: a person counts as tracked within 30 cm (CLEAR-MOT at 0.3 m), everyone in the room counts. TSR
and MR are the matched and missed shares of the persons over all frames, GR the false tracks' share, mismatch the
CLEAR-MOT ID switches (a run's count), MOTP the mean error of the matches in cm, MOTA 1 - (misses + false tracks +
mismatches) / persons. Id swaps (Table 6) count seed 001's way: a pair of persons, in a frame where one of them takes
a track that last followed the other, counts once.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from evaluation.clearmot import ClearMot
from pipeline.fusion import fuse
from pipeline.tracking.rjmcmc import TABLE1_WEIGHTS, RjmcmcTracker, View, views
from pipeline.types import DetectedPersons

from .seeds import map_seeds
from .. import workers
from ..workers import Engine

SEQUENCES = (("I", "seed001_room_1"), ("II", "seed001_room_2"), ("III", "seed001_room_3"))
LEAD_IN = 3.0  # s: 15 frames at 5 Hz, the Sigma-Delta model's bootstrap
THRESHOLD = 0.3  # m, seed 001 Sec. 6: "within a 30 cm radius of the ground truth"
# seed 001 Sec. 6's modes: (label, detector weights k_d, the cameras whose colour the filter weighs). Laser only: "1.0
# for the laser"; cameras only: "0.5 for each camera with equally influential HOG and foreground segmentation"; one
# camera and the laser: "0.4 for the laser and 0.6 for the camera" (split equally; camera 1, as the paper names
# none); all sensors: Table 1.
MODES = (
    ("laser only", {"laser/legs": 1.0, "laser/blobs": 1.0}, ()),
    ("cameras only", {"camera_1/fseg": 0.25, "camera_1/hog": 0.25, "camera_2/fseg": 0.25, "camera_2/hog": 0.25},
     ("camera_1", "camera_2")),
    ("laser + camera 1", {"laser/legs": 0.4, "laser/blobs": 0.4, "camera_1/fseg": 0.3, "camera_1/hog": 0.3},
     ("camera_1",)),
    ("all sensors", TABLE1_WEIGHTS, ("camera_1", "camera_2")),
)
COLUMNS = ("TSR", "MR", "GR", "mismatch", "MOTP cm", "MOTA", "id swaps")
# the pooled likelihood's own parameters are chosen on these (room, seed), never on the sequences above (``tune``)
TRAINING = (("seed001_room_3", 4000), ("seed001_room_2", 4001))
TUNE_START = {"newcomer": 0.001, "looks": 5.0, "survival": 0.6, "p_detect": 0.7}
TUNE_GRID = {"newcomer": [0.0003, 0.001, 0.003], "looks": [1.0, 2.0, 3.0, 5.0], "survival": [0.4, 0.6, 0.8],
             "p_detect": [0.5, 0.7, 0.9]}
TUNE_MARGIN = 0.005
# Tables 2-5 (TSR, MR, GR, mismatch, MOTP cm, MOTA; mean, sd) and Table 6 (id swaps; mean, sd), per mode and sequence
PUBLISHED = {
    "laser only": {"I": [(0.757, 0.034), (0.252, 0.034), (0.396, 0.042), (15.00, 2.618), (15.62, 2.340),
                         (0.410, 0.049), (2.50, 0.76)],
                   "II": [(0.667, 0.033), (0.333, 0.033), (0.527, 0.104), (21.62, 5.450), (19.90, 1.664),
                          (0.273, 0.068), (4.62, 0.74)],
                   "III": [(0.606, 0.044), (0.394, 0.044), (0.541, 0.103), (46.75, 4.921), (21.94, 1.745),
                           (0.202, 0.068), (4.88, 1.35)]},
    "cameras only": {"I": [(0.897, 0.006), (0.103, 0.006), (0.087, 0.034), (7.60, 1.817), (19.80, 0.140),
                           (0.797, 0.025), (0.60, 0.55)],
                     "II": [(0.817, 0.049), (0.182, 0.048), (0.089, 0.017), (19.17, 3.920), (22.79, 1.350),
                            (0.708, 0.05), (1.33, 0.52)],
                     "III": [(0.734, 0.050), (0.265, 0.050), (0.248, 0.016), (57.60, 14.15), (28.44, 1.601),
                             (0.4588, 0.067), (2.40, 0.55)]},
    "laser + camera 1": {"I": [(0.932, 0.023), (0.068, 0.023), (0.110, 0.014), (1.333, 1.633), (17.52, 1.80),
                               (0.825, 0.030), (0.00, 0.00)],
                         "II": [(0.859, 0.032), (0.140, 0.032), (0.147, 0.030), (10.50, 4.680), (17.63, 1.643),
                                (0.713, 0.055), (0.83, 0.41)],
                         "III": [(0.725, 0.037), (0.274, 0.037), (0.339, 0.069), (47.40, 6.986), (22.83, 1.00),
                                 (0.402, 0.051), (1.60, 0.89)]},
    "all sensors": {"I": [(0.935, 0.029), (0.065, 0.022), (0.099, 0.020), (0.667, 0.816), (17.01, 1.886),
                          (0.841, 0.033), (0.00, 0.00)],
                    "II": [(0.885, 0.029), (0.115, 0.029), (0.099, 0.020), (11.40, 3.782), (17.73, 0.005),
                           (0.793, 0.030), (0.40, 0.55)],
                    "III": [(0.755, 0.018), (0.245, 0.018), (0.211, 0.027), (35.60, 5.941), (21.30, 1.358),
                            (0.538, 0.040), (1.20, 1.09)]},
}


@dataclass
class RecordedFrame:
    """One cycle of a recorded sequence: every detector's batches (odom), the wall cameras' colour views and the
    ground truth (everyone in the room)."""

    stamp: float
    batches: dict[str, DetectedPersons]
    views: list[View]
    gt_ids: np.ndarray
    gt_position: np.ndarray


def record(name: str, seed: int | None = None) -> list[RecordedFrame]:
    """The sequence of the bundled scenario ``name`` (at its own seed unless ``seed``), from its lead-in on; the
    frames of the lead-in are left out."""
    from crowdsim.loop import Simulation
    from scenarios import load_scenario

    scenario = load_scenario(name)
    # the filter runs on the recording, in every mode
    scenario = scenario.replace(pipeline=scenario.pipeline.replace(tracker={"type": "nnt"}))
    sim = Simulation(scenario)
    sim.reset(scenario.seed if seed is None else seed)
    sim.warm_up()
    frames = []
    for f in sim.frames(scenario.duration + LEAD_IN):
        if f.stamp > LEAD_IN + 1e-9:
            frames.append(RecordedFrame(f.stamp, f.detector_outputs, views(f.camera_frames),
                                        f.groundtruth.track_id, f.groundtruth.position))
    return frames


def replay(frames: list[RecordedFrame], weights: dict, cameras: tuple, run: int, **params) -> tuple[list, float]:
    """The filter in one mode (``weights``, the ``cameras`` whose colour it weighs) with filter seed ``run``: the
    row of COLUMNS and its mean ms per cycle."""
    tracker = RjmcmcTracker(weights=weights, seed=run, **params)
    score = ClearMot(THRESHOLD)
    swaps = IdSwaps()
    spent = 0.0
    for f in frames:
        batches = {k: v for k, v in f.batches.items() if weights.get(k, 0.0) > 0}
        tracker.look([v for v in f.views if v.name in cameras])
        t = time.perf_counter()
        tracks = tracker.update(f.stamp, fuse(batches, 0.0))
        spent += time.perf_counter() - t
        result = score.update(f.gt_ids, f.gt_position, tracks.track_id, tracks.position)
        swaps.update(result)
    s = score.result()
    row = [s.tsr, s.miss_rate, s.fp_rate, s.id_switches, 100 * (s.motp_m or np.nan), s.mota, swaps.count]
    return row, 1000 * spent / len(frames)


class IdSwaps:
    """Seed 001's id swaps: per frame, each pair of persons of which one takes a track that last followed the
    other, once."""

    def __init__(self):
        self.count = 0
        self._last_person: dict[int, int] = {}  # track -> the person it last followed

    def update(self, result) -> None:
        pairs = set()
        switched = set(result.switched_gt_ids.tolist())
        for person, track in zip(result.matched_gt_ids.tolist(), result.matched_hyp_ids.tolist()):
            before = self._last_person.get(track)
            if person in switched and before is not None and before != person:
                pairs.add((min(person, before), max(person, before)))
            self._last_person[track] = person
        self.count += len(pairs)


def _record_training(index: int) -> list[RecordedFrame]:
    return record(*TRAINING[index])


def tune(engine: Engine = Engine(), progress: bool = True) -> dict:
    """Coordinate search of the pooled likelihood's own parameters (``TUNE_GRID``, from ``TUNE_START``) for the mean
    MOTA over the four modes on the training sequences (filter seed 0); a value replaces the best only if it raises
    the mean by ``TUNE_MARGIN`` or more, about one filter seed's noise. Returns the best and every trial."""
    frames = map_seeds(_record_training, list(range(len(TRAINING))), engine=engine, desc="training sequences",
                       progress=progress)

    def score(params):
        return float(np.mean([replay(f, weights, cameras, 0, **params)[0][COLUMNS.index("MOTA")]
                              for f in frames for _, weights, cameras in MODES]))

    best, best_score, trials = coordinate_search(score, TUNE_START, TUNE_GRID, TUNE_MARGIN, progress)
    return {"best": best, "best_mota": best_score, "trials": trials}


def coordinate_search(score, start: dict, grid: dict, margin: float, progress: bool = False):
    """One sweep over ``grid``'s keys in order: each key's values tried with the others at the best so far, the top
    one kept if it beats the best by ``margin``. Returns the best parameters, their score and every (params, score)."""
    from tqdm import tqdm

    best = dict(start)
    trials = [(dict(best), score(best))]
    best_score = trials[0][1]
    with tqdm(total=sum(len(v) - 1 for v in grid.values()), desc="tune", unit="trial", disable=not progress) as bar:
        for key, values in grid.items():
            tried = [(dict(best), best_score)]
            for value in values:
                if value != best[key]:
                    tried.append(({**best, key: value}, score({**best, key: value})))
                    bar.update()
            trials += tried[1:]
            top = max(tried, key=lambda t: t[1])
            if top[1] >= best_score + margin:
                best, best_score = dict(top[0]), top[1]
    return best, best_score, trials


def _one_sequence(index: int, runs: int) -> dict:
    """Record sequence ``index`` and replay every mode ``runs`` times: the figures [modes, runs, columns] and the
    filter's ms per cycle per mode."""
    frames = record(SEQUENCES[index][1])
    figures, ms = [], []
    for _, weights, cameras in MODES:
        rows = [replay(frames, weights, cameras, run) for run in range(runs)]
        figures.append([row for row, _ in rows])
        ms.append(float(np.mean([t for _, t in rows])))
    return {"figures": figures, "ms": ms, "frames": len(frames)}


def experiment(runs: int = 8, engine: Engine = Engine(), progress: bool = True) -> dict:
    """Every sequence, mode and run: figures [sequences, modes, runs, columns], ms per cycle [sequences, modes]."""
    out = map_seeds(_one_sequence, list(range(len(SEQUENCES))), runs, engine=engine, desc="seed001 sequences",
                    progress=progress)
    return {"figures": np.array([o["figures"] for o in out], float), "ms": np.array([o["ms"] for o in out]),
            "frames": [o["frames"] for o in out], "runs": runs}


def claims(mean: np.ndarray) -> list[tuple[str, bool, str]]:
    """Seed 001's claims (a)-(d) on the mean figures [sequences, modes, columns]: (claim, holds, the numbers)."""
    laser, cameras, one, everything = range(len(MODES))
    mota, motp, swaps = COLUMNS.index("MOTA"), COLUMNS.index("MOTP cm"), COLUMNS.index("id swaps")
    seqs = [label for label, _ in SEQUENCES]

    def per_sequence(values):
        return "; ".join(f"{s}: " + " / ".join(f"{v:.3g}" for v in row) for s, row in zip(seqs, values))

    a = all(mean[s, everything, mota] >= mean[s, :, mota].max() and mean[s, laser, mota] <= mean[s, :, mota].min()
            for s in range(len(seqs)))
    b = all(mean[s, laser, swaps] >= mean[s, cameras, swaps] >= mean[s, one, swaps] >= mean[s, everything, swaps]
            and mean[s, laser, swaps] > mean[s, everything, swaps] for s in range(len(seqs)))
    c = all(mean[0, m, mota] > mean[-1, m, mota] for m in range(len(MODES)))
    d = all(mean[s, cameras, motp] > mean[s, m, motp] for s in range(len(seqs)) for m in (laser, one, everything))
    order = "laser only / cameras only / laser + camera 1 / all sensors"
    return [
        ("(a) all sensors give the best MOTA in every sequence, laser only the worst", a,
         f"MOTA {order}: {per_sequence(mean[:, :, mota])}"),
        ("(b) id swaps fall from laser only to cameras only to laser + camera 1 to all sensors", b,
         f"id swaps {order}: {per_sequence(mean[:, :, swaps])}"),
        ("(c) every mode degrades from sequence I to III (MOTA)", c,
         "MOTA I -> III: " + "; ".join(f"{MODES[m][0]} {mean[0, m, mota]:.3f} -> {mean[-1, m, mota]:.3f}"
                                       for m in range(len(MODES)))),
        ("(d) MOTP is worse with cameras only than with any mode that has the laser", d,
         f"MOTP cm {order}: {per_sequence(mean[:, :, motp])}"),
    ]


def report(results: dict) -> str:
    """Tables 2-6 (ours: mean +- sd over the runs / seed 001's) and the claims."""
    fig = results["figures"]
    mean, sd = np.nanmean(fig, axis=2), np.nanstd(fig, axis=2, ddof=1) if fig.shape[2] > 1 else 0 * fig[:, :, 0]
    lines = [f"Seed 001's Tables 2-6 on our room: {results['runs']} filter runs per sequence and mode "
             f"(mean +- sd; seed 001's after /)"]
    for m, (mode, weights, _) in enumerate(MODES):
        lines += ["", f"Table {m + 2}: {mode} (k_d {weights})", "",
                  "| sequence | " + " | ".join(COLUMNS[:-1]) + " | ms/cycle |", "|---" * len(COLUMNS) + "|---|"]
        for s, (label, _) in enumerate(SEQUENCES):
            cells = [f"{mean[s, m, c]:.3f} +- {sd[s, m, c]:.3f} / {PUBLISHED[mode][label][c][0]:g}"
                     if c not in (3, 4) else
                     f"{mean[s, m, c]:.1f} +- {sd[s, m, c]:.1f} / {PUBLISHED[mode][label][c][0]:g}"
                     for c in range(len(COLUMNS) - 1)]
            lines.append(f"| {label} | " + " | ".join(cells) + f" | {results['ms'][s, m]:.1f} |")
    swaps = COLUMNS.index("id swaps")
    lines += ["", "Table 6: id swaps", "", "| sequence | " + " | ".join(mode for mode, _, _ in MODES) + " |",
              "|---" * (len(MODES) + 1) + "|"]
    for s, (label, _) in enumerate(SEQUENCES):
        lines.append(f"| {label} | " + " | ".join(
            f"{mean[s, m, swaps]:.2f} +- {sd[s, m, swaps]:.2f} / {PUBLISHED[mode][label][swaps][0]:g}"
            for m, (mode, _, _) in enumerate(MODES)) + " |")
    lines += ["", "Claims:"] + [f"- {'holds' if ok else 'DOES NOT HOLD'}: {text} ({numbers})"
                                for text, ok, numbers in claims(mean)]
    return "\n".join(lines)


def plot(results: dict, path) -> None:
    """MOTA and MOTP per sequence and mode, ours (mean and sd over the runs) beside seed 001's."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = results["figures"]
    fig_mean, fig_sd = np.nanmean(fig, axis=2), np.nanstd(fig, axis=2)
    x = np.arange(len(SEQUENCES))
    width = 0.2
    plots, axes = plt.subplots(1, 2, figsize=(12, 4.5))
    for ax, column in zip(axes, ("MOTA", "MOTP cm")):
        c = COLUMNS.index(column)
        for m, (mode, _, _) in enumerate(MODES):
            offset = (m - 1.5) * width
            published = [PUBLISHED[mode][label][c][0] for label, _ in SEQUENCES]
            bars = ax.bar(x + offset, fig_mean[:, m, c], width * 0.9, yerr=fig_sd[:, m, c], label=f"ours, {mode}")
            ax.scatter(x + offset, published, marker="_", s=300, color=bars.patches[0].get_facecolor(),
                       edgecolors="black", zorder=3)
        ax.set_xticks(x, [f"sequence {label}" for label, _ in SEQUENCES])
        ax.set_title(f"{column} (bars: ours; dashes: seed 001)")
        ax.grid(axis="y", alpha=0.3)
    axes[0].legend(fontsize=8)
    plots.tight_layout()
    plots.savefig(path, dpi=110)
    plt.close(plots)


def write(out, results: dict) -> str:
    """Write seed001.md, seed001.json (every run's figures) and seed001.png into ``out``; returns the report."""
    import json
    from pathlib import Path

    out = Path(out)
    text = report(results)
    (out / "seed001.md").write_text(text + "\n")
    (out / "seed001.json").write_text(json.dumps({
        "sequences": [{"label": label, "scenario": name, "frames": n}
                      for (label, name), n in zip(SEQUENCES, results["frames"])],
        "modes": [{"label": mode, "weights": weights, "cameras": list(cameras)} for mode, weights, cameras in MODES],
        "columns": list(COLUMNS), "runs": results["runs"], "threshold_m": THRESHOLD, "lead_in_s": LEAD_IN,
        "figures": np.where(np.isfinite(results["figures"]), results["figures"], None).tolist(),
        "ms_per_cycle": results["ms"].tolist(), "published": PUBLISHED}, indent=1) + "\n")
    plot(results, out / "seed001.png")
    return text


def write_tuning(out, result: dict) -> str:
    """Write tune.md (every trial, the best) and tune.json into ``out``; returns the report."""
    import json
    from pathlib import Path

    keys = list(TUNE_START)
    lines = [f"Coordinate search on {', '.join(f'{n} seed {s}' for n, s in TRAINING)}: mean MOTA over the four modes "
             f"(filter seed 0); a change must gain {TUNE_MARGIN}", "",
             "| " + " | ".join(keys) + " | mean MOTA |", "|---" * (len(keys) + 1) + "|"]
    lines += ["| " + " | ".join(f"{p[k]:g}" for k in keys) + f" | {mota:.3f} |" for p, mota in result["trials"]]
    lines += ["", "Best: " + ", ".join(f"{k} {result['best'][k]:g}" for k in keys) + f" (mean MOTA "
              f"{result['best_mota']:.3f})"]
    text = "\n".join(lines)
    (Path(out) / "tune.md").write_text(text + "\n")
    (Path(out) / "tune.json").write_text(json.dumps({"training": [list(t) for t in TRAINING], "grid": TUNE_GRID,
                                                     "start": TUNE_START, "margin": TUNE_MARGIN, **result},
                                                    indent=1) + "\n")
    return text


def add_arguments(parser) -> None:
    from ..cli import add_out_argument

    parser.add_argument("--runs", type=int, default=8, help="filter runs per sequence and mode (default 8, as seed "
                                                            "001's)")
    parser.add_argument("--tune", action="store_true", help="choose the filter's pooled-likelihood parameters on "
                                                            "training sequences (rooms 3 and 2 at seeds 4000, 4001) "
                                                            "in place of the tables: tune.md, tune.json")
    workers.add_arguments(parser)
    add_out_argument(parser, "seed001")


def main(args) -> int:
    """``crowdsim experiment seed001``."""
    from ..cli import UsageError, run_dir
    from ..outdir import write_directory

    if args.runs < 1 or args.workers < 1:
        raise UsageError(f"--runs and --workers: expected at least 1, got {args.runs} and {args.workers}")
    out = run_dir(args, "seed001")
    if args.tune:
        print(write_directory(out, lambda tmp: write_tuning(tmp, tune(engine=Engine(args.workers, args.ray)))))
        return 0
    results = experiment(args.runs, engine=Engine(args.workers, args.ray))
    print(write_directory(out, lambda tmp: write(tmp, results)))
    print(f"\n{out / 'seed001.md'}, seed001.json, seed001.png")
    return 0

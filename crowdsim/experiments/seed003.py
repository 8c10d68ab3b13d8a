"""``crowdsim experiment seed003``: seed 003's Tables 2-5 (Munaro & Menegatti, Sec. 4.1) on our KTP-like room, beside
the published values, and its claims checked one by one.

Runs. KTP holds four videos, one per robot motion (still, translation, rotation, arc), each with the five situations
(back and forth, random walk, side by side, running, group). Ours are the bundled ``ktp_<situation>`` scenarios under
each motion's ``robot.script``: 20 runs a seed, at evaluation seeds from 1 (the HOG model trains on 5100-5201). Each
run is simulated once; the detector and tracker then replay its depth frames in every variant: full; no sub-clustering
(Table 2's "No sub."); no appearance (the colour term left out of the association: our stand-in for Table 2's Basso
et al. 2012 row, which used colour only to re-identify); the classifiers frozen after initialisation (claim e); HSV
(Table 6's recommended colour space).

Scoring as seed 003 Sec. 4.1.1, at each camera frame:
- 2D: the persons the image shows at least half of (KTP's labelling rule; those shown less take part in the matching
  but count neither as misses nor, matched, as false positives), each with the box of their silhouette's full height,
  half as wide, clipped to the image; each track's box the same from its floor position and height, where it falls in
  the image. Matched at intersection over union 0.5 or more; MOTP the mean IoU of the matches (in %).
- 3D: the same persons and tracks on the floor (odometry frame), matched within 0.3 m; MOTP in m.
- ID switches split: a re-entry when the person had been out of the annotation for ``REENTRY_GAP`` s or more before
  the switch ("a person exits the scene and re-appears after several seconds"), the others.
Rates are pooled over the runs of a row (instances summed), as Table 2's aggregate is.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from evaluation.clearmot import ClearMot
from pipeline.detectors.hog import box_iou
from pipeline.detectors.rgbd import RgbdPeopleDetector, person_box
from pipeline.fusion import to_frame
from pipeline.tracking.rgbd_tracker import RgbdTracker
from pipeline.types import DepthFrame
from scenarios.typed import Scenario

from .seeds import map_seeds
from .train_hog_robot import recording, truth_boxes
from .. import workers
from ..workers import Engine

SITUATIONS = ("back_and_forth", "random_walk", "side_by_side", "running", "group")
SITUATION_LABELS = ("Back and forth", "Random walk", "Side by side", "Running", "Group")
# robot.script rows [duration s, v m/s, omega rad/s] within KTP's 0.15 m/s and 0.11 rad/s (seed 003 Sec. 2)
# (each lap ends where it began; the robot stays in the room and turns within +-0.4 rad, so people stay in view)
MOTIONS = {
    "still": [[1000.0, 0.0, 0.0]],
    "translation": [[6.0, 0.15, 0.0], [12.0, -0.15, 0.0], [6.0, 0.15, 0.0]],
    "rotation": [[3.6, 0.0, 0.11], [8.0, 0.0, -0.11], [4.4, 0.0, 0.11]],
    "arc": [[7.0, 0.15, 0.06], [14.0, -0.15, -0.06], [7.0, 0.15, 0.06]],
}
VARIANTS = {  # label -> (detector parameters, tracker parameters)
    "full": ({}, {}),
    "no sub-clustering": ({"sub_clustering": False}, {}),
    "no appearance": ({}, {"appearance_weight": 0.0}),
    "frozen classifiers": ({}, {"learn": False}),
    "hsv": ({"colour_space": "hsv"}, {"colour_space": "hsv"}),
}
MIN_VISIBLE = 0.5  # KTP annotates people at least half visible
IOU, DISTANCE = 0.5, 0.3  # the 2D and 3D match rules (Sec. 4.1.1)
REENTRY_GAP = 1.0  # s out of the annotation before a switch that makes it a re-entry
FIRST_SEED = 1
COLUMNS = ("MOTP", "MOTA %", "FP %", "FN %", "ID Sw.", "re-entries")
# Tables 2-5 (MOTP, MOTA, FP, FN, ID switches, re-entries); Table 2's third row is Basso et al. 2012's system
PUBLISHED_2 = {"full": (84.24, 86.1, 0.8, 12.7, 60, None), "no sub-clustering": (84.2, 83.02, 0.6, 15.9, 56, None),
               "no appearance": (86, 82.41, 0.9, 16.1, 82, None), "hsv": (84.22, 85.8, 0.7, 12.5, 53, None)}
PUBLISHED_3 = {"still": (83.76, 88.86, 0.9, 9.8, 15, None), "translation": (84.39, 88.03, 0.8, 10.7, 15, None),
               "rotation": (84.19, 83.16, 0.9, 15.4, 19, None), "arc": (84.89, 83.24, 0.8, 15.5, 13, None)}
PUBLISHED_4 = {"back_and_forth": (84.23, 89.17, 0.9, 9.9, 1, 0), "random_walk": (84.4, 86.42, 1, 12.3, 22, 0),
               "side_by_side": (84.6, 79.12, 0.6, 20.2, 5, 5), "running": (80.79, 90.44, 0.9, 8.7, 4, 4),
               "group": (83.59, 63, 0.8, 35.8, 32, 16)}
PUBLISHED_5 = {"back_and_forth": (0.196, 88.97, 2.4, 8.5, 1, 0), "random_walk": (0.171, 70.93, 9.8, 18.9, 20, 0),
               "side_by_side": (0.146, 87.22, 1.2, 11.6, 5, 5), "running": (0.143, 94.57, 1.1, 4.4, 4, 4),
               "group": (0.181, 47.91, 9.1, 42.53, 26, 16)}


@dataclass
class Recorded:
    """One camera frame of a run and the ground truth of the persons in it (floor positions in odom)."""

    image: DepthFrame
    gt_ids: np.ndarray
    gt_xy: np.ndarray


def scenario(situation: str, motion: str, preset: str = "kinect_160") -> Scenario:
    from scenarios import scenario_from_dict
    from scenarios.loader import read_raw, resolve

    raw = read_raw(resolve(f"ktp_{situation}"))
    raw["robot"] = {**raw["robot"], "driver": "script", "script": MOTIONS[motion], "loop": True}
    raw["sensors"]["depth_cameras"][0]["preset"] = preset
    return scenario_from_dict(recording(raw), f"seed003 {situation} {motion}")


def record(situation: str, motion: str, seed: int, preset: str = "kinect_160") -> list[Recorded]:
    """The camera frames of one run, with the true floor positions of the persons they show."""
    from crowdsim.loop import Simulation

    sim = Simulation(scenario(situation, motion, preset))
    sim.reset(seed)
    out = []
    for frame in sim.frames(sim.scenario.duration):
        for image in frame.depth_frames:
            gt = frame.groundtruth
            rows = np.searchsorted(gt.track_id, image.ids)
            known = rows < len(gt.track_id)
            known[known] = gt.track_id[rows[known]] == image.ids[known]
            image.depth = image.person_id = None  # the replay needs points, colour, calibration and the truth
            out.append(Recorded(image, image.ids[known], gt.position[rows[known]]))
    return out


class Scores:
    """CLEAR-MOT of one row in 2D and 3D, with ID switches split into re-entries and others."""

    def __init__(self):
        self.box, self.floor = ClearMot(1 - IOU), ClearMot(DISTANCE)
        self.reentries = {"2d": 0, "3d": 0}
        self._last_seen: dict[int, float] = {}

    def update(self, frame: Recorded, tracks) -> None:
        image = frame.image
        shown = np.isin(image.ids, frame.gt_ids)
        ids, boxes = image.ids[shown], clip(truth_boxes(image.full_boxes[shown]), image)
        ignore = image.visible_fraction[shown] < MIN_VISIBLE
        xy = frame.gt_xy  # in the order of the image's ids, as ``ids``
        track_boxes = track_boxes_in(image, tracks)
        inside = (track_boxes[:, 2] > track_boxes[:, 0]) & (track_boxes[:, 3] > track_boxes[:, 1])
        hyp = tracks.track_id[inside]
        iou = box_iou(boxes, track_boxes[inside]) if len(boxes) and inside.any() else np.zeros((len(ids), len(hyp)))
        results = {"2d": self.box.update_dissimilarity(ids, hyp, 1 - iou, ignore),
                   "3d": self.floor.update(ids, xy, hyp, tracks.position[inside], ignore)}
        counted = ids[~ignore]
        for kind, result in results.items():
            for person in result.switched_gt_ids.tolist():
                if image.stamp - self._last_seen.get(person, image.stamp) >= REENTRY_GAP:
                    self.reentries[kind] += 1
        self._last_seen.update({int(p): image.stamp for p in counted})

    def counts(self) -> dict:
        """Per kind: instances, matches, FP, FN, ID switches, re-entries and the summed match quality."""
        out = {}
        for kind, score in (("2d", self.box), ("3d", self.floor)):
            s = score.result()
            quality = s.matches * (s.motp_m or 0.0)
            if kind == "2d":
                quality = s.matches - quality  # 1 - IoU summed: IoU summed
            out[kind] = [s.gt, s.matches, s.fp, s.fn, s.id_switches, self.reentries[kind], quality]
        return out


def clip(boxes: np.ndarray, image: DepthFrame) -> np.ndarray:
    h, w = image.rgb.shape[:2]
    return np.column_stack([np.clip(boxes[:, [0, 2]], 0, w), np.clip(boxes[:, [1, 3]], 0, h)])[:, [0, 2, 1, 3]]


def track_boxes_in(image: DepthFrame, tracks) -> np.ndarray:
    """Each track's box in the image (clipped; empty where it is behind the camera or out of view): from its floor
    point up its height (1.7 m when the tracker gives none), half as wide as high."""
    n = len(tracks)
    if not n:
        return np.zeros((0, 4))
    height = tracks.height if tracks.height is not None else np.full(n, 1.7)
    world_to_camera = np.linalg.inv(image.pose)
    floor = np.column_stack([tracks.position, np.zeros(n), np.ones(n)]) @ world_to_camera.T
    normal = world_to_camera[:3, :3] @ [0.0, 0.0, 1.0]
    ahead = floor[:, 2] > 0.1
    boxes = np.zeros((n, 4))
    if ahead.any():
        boxes[ahead] = clip(person_box(image.camera_matrix, floor[ahead, :3], normal, height[ahead]), image)
    return boxes


def replay(frames: list[Recorded], detector_params: dict, tracker_params: dict) -> tuple[Scores, float]:
    """The detector and tracker on a recorded run: its scores and the ms per frame they took."""
    detector, tracker = RgbdPeopleDetector(**detector_params), RgbdTracker(**tracker_params)
    scores = Scores()
    spent = 0.0
    for frame in frames:
        t0 = time.perf_counter()
        image = frame.image
        detections = to_frame(detector.detect(image), image.pose, "odom")
        tracker.see([image])
        tracks = tracker.update(image.stamp, detections)
        spent += time.perf_counter() - t0
        scores.update(frame, tracks)
    return scores, 1000 * spent / max(len(frames), 1)


def _one_run(index: int, seeds: int, preset: str) -> dict:
    situation, motion, seed = runs(seeds)[index]
    frames = record(situation, motion, seed, preset)
    out = {"situation": situation, "motion": motion, "seed": seed, "frames": len(frames), "counts": {}, "ms": {}}
    for label, (detector_params, tracker_params) in VARIANTS.items():
        scores, ms = replay(frames, detector_params, tracker_params)
        out["counts"][label], out["ms"][label] = scores.counts(), ms
    return out


def runs(seeds: int) -> list[tuple[str, str, int]]:
    return [(s, m, seed) for seed in range(FIRST_SEED, FIRST_SEED + seeds) for m in MOTIONS for s in SITUATIONS]


def experiment(seeds: int = 1, engine: Engine = Engine(), preset: str = "kinect_160", progress: bool = True) -> dict:
    """Every situation under every motion, ``seeds`` times: each run's counts per variant and kind."""
    out = map_seeds(_one_run, list(range(len(runs(seeds)))), seeds, preset, engine=engine,
                    desc="seed003 runs", progress=progress)
    return {"runs": out, "seeds": seeds, "preset": preset}


def row(results: dict, variant: str, kind: str, **where) -> tuple:
    """(MOTP, MOTA %, FP %, FN %, ID switches, re-entries) pooled over the runs matching ``where``."""
    total = np.zeros(7)
    for run in results["runs"]:
        if all(run[k] == v for k, v in where.items()):
            total += run["counts"][variant][kind]
    gt, matches, fp, fn, ids, reentries, quality = total
    if not gt:
        return (np.nan,) * 4 + (0, 0)
    motp = quality / matches * (100 if kind == "2d" else 1) if matches else np.nan
    return (motp, 100 * (1 - (fp + fn + ids) / gt), 100 * fp / gt, 100 * fn / gt, int(ids), int(reentries))


def claims(results: dict) -> list[tuple[str, bool, str]]:
    """Seed 003's claims (a)-(e): (claim, holds, the numbers)."""
    def mota(variant="full", kind="2d", **where):
        return row(results, variant, kind, **where)[1]

    def fn(variant="full", **where):
        return row(results, variant, "2d", **where)[3]

    gain = {s: mota(situation=s) - mota("no sub-clustering", situation=s) for s in SITUATIONS}
    fn_drop = {s: fn("no sub-clustering", situation=s) - fn(situation=s) for s in SITUATIONS}
    top = sorted(SITUATIONS, key=lambda s: -gain[s])[:2]
    a = fn() < fn("no sub-clustering") and mota() > mota("no sub-clustering") and set(top) == {"side_by_side", "group"}
    motas = {k: {s: mota(kind=k, situation=s) for s in SITUATIONS} for k in ("2d", "3d")}
    b = all(min(m, key=m.get) == "group" for m in motas.values())
    others = {k: {s: row(results, "full", k, situation=s)[4] - row(results, "full", k, situation=s)[5]
                  for s in SITUATIONS} for k in ("2d", "3d")}
    c = all(max(o, key=o.get) == "random_walk" and list(o.values()).count(o["random_walk"]) == 1
            for o in others.values())
    by_motion = {m: mota(motion=m) for m in MOTIONS}
    d = max(by_motion["rotation"], by_motion["arc"]) < min(by_motion["still"], by_motion["translation"])
    e = mota("frozen classifiers") < mota()

    def listing(values, fmt="{:.1f}"):
        return ", ".join(f"{k} " + fmt.format(v) for k, v in values.items())

    return [
        ("(a) sub-clustering lowers FN and raises MOTA, most in side by side and group", a,
         f"FN {fn('no sub-clustering'):.1f}% -> {fn():.1f}%, MOTA {mota('no sub-clustering'):.1f}% -> {mota():.1f}%; "
         f"MOTA gain per situation: {listing(gain)}; FN drop: {listing(fn_drop)}"),
        ("(b) the group situation is the hardest (lowest MOTA, 2D and 3D)", b,
         f"MOTA 2D: {listing(motas['2d'])}; 3D: {listing(motas['3d'])}"),
        ("(c) random walk has the most ID switches that are not re-entries", c,
         f"2D: {listing(others['2d'], '{:g}')}; 3D: {listing(others['3d'], '{:g}')}"),
        ("(d) rotation and arc are harder than still and translation (MOTA)", d, listing(by_motion)),
        ("(e) freezing the appearance classifiers lowers MOTA (seed 003: by 7%)", e,
         f"MOTA full {mota():.1f}%, frozen {mota('frozen classifiers'):.1f}%"),
    ]


def _table(title: str, rows: list[tuple[str, tuple, tuple | None]], motp_unit: str) -> list[str]:
    lines = ["", title, "", f"| | MOTP {motp_unit} | MOTA % | FP % | FN % | ID Sw. (re-entries) |", "|---" * 6 + "|"]
    for label, ours, published in rows:
        motp_fmt = "{:.3f}" if motp_unit == "m" else "{:.1f}"
        cells = [motp_fmt.format(ours[0]), f"{ours[1]:.1f}", f"{ours[2]:.1f}", f"{ours[3]:.1f}",
                 f"{ours[4]} ({ours[5]})"]
        if published is not None:
            cells = [f"{c} / {p:g}" for c, p in zip(cells[:4], published[:4])] + [
                f"{cells[4]} / {published[4]}" + (f" ({published[5]})" if published[5] is not None else "")]
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    return lines


def report(results: dict) -> str:
    n = len(results["runs"])
    frames = sum(r["frames"] for r in results["runs"])
    ms = {v: np.mean([r["ms"][v] for r in results["runs"]]) for v in VARIANTS}
    lines = [f"Seed 003's Tables 2-5 on our KTP-like room: {n} runs ({results['seeds']} seed(s) x 4 motions x 5 "
             f"situations, {frames} camera frames, {results['preset']}); ours / seed 003's"]
    lines += _table("Table 2: variants (2D; seed 003's third row is Basso et al. 2012's system)",
                    [(v, row(results, v, "2d"), PUBLISHED_2.get(v)) for v in VARIANTS], "%")
    lines += _table("Table 3: per robot motion (2D, full)",
                    [(m, row(results, "full", "2d", motion=m), PUBLISHED_3[m]) for m in MOTIONS], "%")
    lines += _table("Table 4: per situation (2D, full)",
                    [(label, row(results, "full", "2d", situation=s), PUBLISHED_4[s])
                     for s, label in zip(SITUATIONS, SITUATION_LABELS)], "%")
    lines += _table("Table 5: per situation (3D, full)",
                    [(label, row(results, "full", "3d", situation=s), PUBLISHED_5[s])
                     for s, label in zip(SITUATIONS, SITUATION_LABELS)], "m")
    lines += _table("Per situation without sub-clustering (2D; seed 003 gives only the total)",
                    [(label, row(results, "no sub-clustering", "2d", situation=s), None)
                     for s, label in zip(SITUATIONS, SITUATION_LABELS)], "%")
    lines += ["", "Detector + tracker, ms per frame: " + ", ".join(f"{v} {t:.1f}" for v, t in ms.items())]
    lines += ["", "Claims:"] + [f"- {'holds' if ok else 'DOES NOT HOLD'}: {text} ({numbers})"
                                for text, ok, numbers in claims(results)]
    return "\n".join(lines)


def plot(results: dict, path) -> None:
    """MOTA per situation (2D and 3D) and per motion, ours beside seed 003's."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(1, 3, figsize=(15, 4.5))
    groups = [("per situation, 2D", [row(results, "full", "2d", situation=s)[1] for s in SITUATIONS],
               [PUBLISHED_4[s][1] for s in SITUATIONS], SITUATION_LABELS),
              ("per situation, 3D", [row(results, "full", "3d", situation=s)[1] for s in SITUATIONS],
               [PUBLISHED_5[s][1] for s in SITUATIONS], SITUATION_LABELS),
              ("per robot motion, 2D", [row(results, "full", "2d", motion=m)[1] for m in MOTIONS],
               [PUBLISHED_3[m][1] for m in MOTIONS], tuple(MOTIONS))]
    for ax, (title, ours, published, labels) in zip(axes, groups):
        x = np.arange(len(labels))
        ax.bar(x - 0.2, ours, 0.4, label="ours")
        ax.bar(x + 0.2, published, 0.4, label="seed 003 (KTP)")
        ax.set_xticks(x, labels, rotation=20)
        ax.set_title(f"MOTA % {title}")
        ax.grid(axis="y", alpha=0.3)
    axes[0].legend(loc="lower left")
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def write(out, results: dict) -> str:
    """Write seed003.md, seed003.json (every run's counts) and seed003.png into ``out``; returns the report."""
    import json
    from pathlib import Path

    out = Path(out)
    text = report(results)
    (out / "seed003.md").write_text(text + "\n")
    (out / "seed003.json").write_text(json.dumps({
        "preset": results["preset"], "seeds": results["seeds"], "motions": MOTIONS, "variants": VARIANTS,
        "counts_order": ["instances", "matches", "fp", "fn", "id_switches", "reentries", "match_quality_sum"],
        "runs": results["runs"]}, indent=1) + "\n")
    plot(results, out / "seed003.png")
    return text


def add_arguments(parser) -> None:
    from ..cli import add_out_argument

    parser.add_argument("--seeds", type=int, default=1, help=f"evaluation seeds from {FIRST_SEED}, each 20 runs "
                                                             "(default 1)")
    parser.add_argument("--preset", choices=("kinect_160", "kinect_640"), default="kinect_160",
                        help="the robot camera's resolution (default kinect_160, QQVGA, as seed 003's timing)")
    workers.add_arguments(parser)
    add_out_argument(parser, "seed003")


def main(args) -> int:
    """``crowdsim experiment seed003``."""
    from ..cli import UsageError, run_dir
    from ..outdir import write_directory

    if args.seeds < 1 or args.workers < 1:
        raise UsageError(f"--seeds and --workers: expected at least 1, got {args.seeds} and {args.workers}")
    out = run_dir(args, "seed003")
    results = experiment(args.seeds, engine=Engine(args.workers, args.ray), preset=args.preset)
    print(write_directory(out, lambda tmp: write(tmp, results)))
    print(f"\n{out / 'seed003.md'}, seed003.json, seed003.png")
    return 0

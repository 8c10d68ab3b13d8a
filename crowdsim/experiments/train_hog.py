"""``crowdsim experiment train-hog``: trains the wall-camera HOG person detector (pipeline/detectors/hog.py) on this
testbed's own rendered images and their exact boxes, as Dalal & Triggs trained theirs on INRIA's photographs.

Data. Seed 001's room (``seed001_room_1``'s cameras, walls and furniture) with a stream of walkers in place of the
sequences' few: people enter at the room's south and north edges, cross it and leave at the other, so many different
people (clothes follow the person's id) pass both cameras. The sequences' own people are ids 1-4; here they are never
positives, and their boxes are kept clear of negatives, so no sequence person is learnt. Seeds: training 4100..4100+N-1,
validation 4200-4201 (the threshold); the sequences' evaluations use seeds 1-8 and the leg tuning 4000-4002.

Windows. Positives: each person with 70% or more of its silhouette visible, its whole silhouette inside the image and
at least ``MIN_HEIGHT`` pixels high, and its mirror image (Dalal & Triggs add reflections). Negatives: ``NEGATIVES``
random windows an image at random scales, overlapping no person's box by more than 0.2; then one round of hard
negatives (Dalal & Triggs): an image's ``NEGATIVES`` best-scored windows of the first model (above -1) that overlap no
person by more than 0.3.
Comparison (``compare_opencv``, ``crowdsim experiment hog-vs-opencv``): our model and OpenCV's INRIA-trained default
people detector on held-out seeds 4300-4301, each at its peak F1 there, ours also at its own threshold.
Classifier: scikit-learn's LinearSVC (C = 0.01, Dalal & Triggs's soft linear SVM), needs the ``[train]`` extra; saved
as plain arrays. Threshold: the score of peak F1 on the validation seeds, a detection right at intersection over
union 0.5 or more with a person's visible box.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pipeline.detectors.hog import (MODEL_FILE, MODEL_FORMAT, MODELS_DIR, PERSON_SHARE, WINDOW_CELLS, HogModel,
                                    box_iou, integral, non_maximum_suppression, orientation_votes, person_in_window,
                                    window_features)
from pipeline.detectors.wall_camera import HOG_SCALES
from scenarios import scenario_from_dict
from scenarios.loader import read_raw, resolve
from scenarios.typed import Scenario

from .seeds import map_seeds
from .. import workers
from ..workers import Engine

SCENARIO = "seed001_room_1"
TRAIN_SEED, VALIDATION_SEEDS, TEST_SEEDS = 4100, (4200, 4201), (4300, 4301)
DURATION, START, EVERY = 60.0, 10.0, 5  # s run, s before the first image kept, tracker cycles between images kept
SEQUENCE_IDS = 4  # the sequences' people: ids 1..4
MIN_HEIGHT, MIN_VISIBLE = 64, 0.7
NEGATIVES = 20
SVM_C = 0.01
SCALES = np.array(HOG_SCALES)  # the detector's: negatives, hard negatives and the threshold at the scales it searches


def stream_scenario() -> Scenario:
    """The room with walkers streaming across it (module docstring)."""
    raw = read_raw(resolve(SCENARIO))
    raw.pop("clusters")
    raw["waypoints"] = {**raw["waypoints"], "south_door": {"position": [5.0, 0.4], "radius": 0.6},
                        "north_door": {"position": [5.0, 7.8], "radius": 0.6}}
    raw["routes"] = {"north": {"waypoints": ["north_door"], "sink": True},
                     "south": {"waypoints": ["south_door"], "sink": True}}
    raw["sources"] = [{"position": [3.0, 0.8], "size": [5.0, 0.5], "rate": 0.15, "routes": {"north": 1}},
                      {"position": [7.0, 7.4], "size": [5.0, 0.5], "rate": 0.15, "routes": {"south": 1}}]
    raw["name"] = "seed001_room_stream"
    return scenario_from_dict(raw, "train-hog stream")


@dataclass
class Images:
    """The kept images of one seed: per image the colour image, its persons' visible boxes, and whether each is a
    positive."""

    rgb: list[np.ndarray]
    boxes: list[np.ndarray]
    positive: list[np.ndarray]


def collect(seed: int, duration: float = DURATION) -> Images:
    from crowdsim.loop import Simulation

    sim = Simulation(stream_scenario())
    sim.reset(seed)
    out = Images([], [], [])
    for k, frame in enumerate(sim.frames(duration)):
        if frame.stamp < START or k % EVERY:
            continue
        for image in frame.camera_frames:
            full = image.full_boxes
            h, w = image.rgb.shape[:2]
            inside = (full[:, 0] >= 0) & (full[:, 1] >= 0) & (full[:, 2] <= w) & (full[:, 3] <= h)
            positive = (inside & (image.visible_fraction >= MIN_VISIBLE) & (full[:, 3] - full[:, 1] >= MIN_HEIGHT)
                        & (image.ids > SEQUENCE_IDS))
            out.rgb.append(image.rgb)
            out.boxes.append(np.asarray(image.boxes, float))
            out.positive.append(positive)
    return out


def windows(data: Images, rng: np.random.Generator, model: HogModel | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Features and labels of the positives (and mirrors) and negatives of every image; with ``model``, its hard
    negatives instead of random ones."""
    xs, ys = [], []
    for rgb, boxes, positive in zip(data.rgb, data.boxes, data.positive):
        h, w = rgb.shape[:2]
        table = integral(orientation_votes(rgb))
        mirror = integral(orientation_votes(rgb[:, ::-1]))
        pos = boxes[positive]
        if len(pos):
            flipped = np.column_stack([w - pos[:, 2], pos[:, 1], w - pos[:, 0], pos[:, 3]])
            xs += [window_features(table, pos).astype(np.float32), window_features(mirror, flipped).astype(np.float32)]
            ys += [np.ones(2 * len(pos))]
        if model is None:
            neg = random_windows(rng, w, h, NEGATIVES)
        else:
            neg, _ = model.detect(rgb, SCALES, overlap=0.3)  # best first
        if len(boxes) and len(neg):
            neg = neg[box_iou(neg, boxes).max(axis=1) <= (0.2 if model is None else 0.3)]
        neg = neg[:NEGATIVES]
        if len(neg):
            xs.append(window_features(table, neg).astype(np.float32))
            ys.append(np.zeros(len(neg)))
    return np.concatenate(xs), np.concatenate(ys)


def random_windows(rng: np.random.Generator, w: int, h: int, n: int) -> np.ndarray:
    """``n`` person boxes of windows at random scales and places inside a w x h image."""
    scale = SCALES[rng.integers(0, len(SCALES), n)]
    win_h, win_w = 8 * WINDOW_CELLS[0] * scale, 8 * WINDOW_CELLS[1] * scale
    ok = (win_h < h) & (win_w < w)
    scale, win_h, win_w = scale[ok], win_h[ok], win_w[ok]
    u0 = rng.uniform(0, 1, len(scale)) * (w - win_w)
    v0 = rng.uniform(0, 1, len(scale)) * (h - win_h)
    margin_v = win_h * (1 - PERSON_SHARE) / 2
    return np.column_stack([u0 + win_w / 4, v0 + margin_v, u0 + 3 * win_w / 4, v0 + win_h - margin_v])


def fit(x: np.ndarray, y: np.ndarray) -> HogModel:
    from sklearn.svm import LinearSVC

    svm = LinearSVC(C=SVM_C, dual=True, max_iter=20_000, random_state=0).fit(x, y)
    return HogModel(svm.coef_[0].astype(np.float32), float(svm.intercept_[0]), 0.0)


def peak_f1_threshold(model: HogModel, data: Images) -> tuple[float, dict]:
    """The score threshold of peak F1 over the images (a detection right at IoU 0.5 or more with a person's visible
    box, each person matched once, best scores first), and the scores there."""
    low = HogModel(model.weight, model.bias, -1.0)
    return peak_f1([low.detect(rgb, SCALES) for rgb in data.rgb], data.boxes)


def peak_f1(detections: list, persons: list) -> tuple[float, dict]:
    """Over images with ``detections`` (boxes, scores) and ``persons`` (visible boxes): the threshold of peak F1 (a
    detection right at IoU 0.5 or more with a person not yet matched, best scores first) and the scores there."""
    scores, hits, n_persons = [], [], 0
    for (found, s), boxes in zip(detections, persons):
        n_persons += len(boxes)
        taken = np.zeros(len(boxes), bool)
        for k in np.argsort(-s).tolist():
            hit = False
            if len(boxes):
                iou = box_iou(found[k:k + 1], boxes)[0]
                iou[taken] = 0
                j = int(iou.argmax())
                if iou[j] >= 0.5:
                    taken[j] = hit = True
            scores.append(s[k])
            hits.append(hit)
    order = np.argsort(-np.array(scores))
    tp = np.cumsum(np.array(hits)[order])
    precision = tp / np.arange(1, len(tp) + 1)
    recall = tp / max(n_persons, 1)
    f1 = 2 * precision * recall / np.maximum(precision + recall, 1e-12)
    best = int(f1.argmax())
    return float(np.array(scores)[order][best]), {"f1": float(f1[best]), "precision": float(precision[best]),
                                                   "recall": float(recall[best]), "persons": n_persons}


def opencv_people(rgb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """OpenCV's default people detector (Dalal & Triggs's INRIA-trained HOG and linear SVM) on our scales (1.2 apart,
    8-pixel steps), every window above -1 with its person box as ours (3/4 of the window's height, its middle half
    across), then our non-maximum suppression: person boxes and scores."""
    import cv2

    hog = cv2.HOGDescriptor()
    hog.setSVMDetector(cv2.HOGDescriptor_getDefaultPeopleDetector())
    windows, scores = hog.detectMultiScale(np.ascontiguousarray(rgb[..., ::-1]), hitThreshold=-1.0,
                                           winStride=(8, 8), scale=1.2, groupThreshold=0)
    u, v, w, h = np.asarray(windows, float).reshape(-1, 4).T  # OpenCV's (x, y, width, height)
    boxes, scores = person_in_window(u, v, w, h), np.asarray(scores, float).reshape(-1)
    keep = non_maximum_suppression(boxes, scores, 0.5)
    return boxes[keep], scores[keep]


def compare_opencv(duration: float = DURATION, engine: Engine = Engine()) -> dict:
    """Our shipped model against OpenCV's INRIA-trained one on the held-out ``TEST_SEEDS``: each one's peak F1 (its
    best threshold there) and ours at its own threshold (chosen on the validation seeds)."""
    from pipeline.detectors.hog import load_model

    data = map_seeds(collect, list(TEST_SEEDS), duration, engine=engine, desc="hog vs opencv")
    test = Images(*(sum((getattr(d, f) for d in data), []) for f in ("rgb", "boxes", "positive")))
    ours = load_model()
    low = HogModel(ours.weight, ours.bias, -1.0)
    found = [low.detect(rgb, SCALES) for rgb in test.rgb]
    at_threshold = [(b[s > ours.threshold], s[s > ours.threshold]) for b, s in found]
    return {"test_seeds": list(TEST_SEEDS), "images": len(test.rgb),
            "ours_peak": peak_f1(found, test.boxes)[1], "ours_at_threshold": peak_f1(at_threshold, test.boxes)[1],
            "opencv_peak": peak_f1([opencv_people(rgb) for rgb in test.rgb], test.boxes)[1]}


def train(n_seeds: int = 10, engine: Engine = Engine(), duration: float = DURATION) -> tuple[HogModel, dict]:
    seeds = list(range(TRAIN_SEED, TRAIN_SEED + n_seeds))
    data = map_seeds(collect, seeds + list(VALIDATION_SEEDS), duration, engine=engine, desc="train-hog")
    training = Images(*(sum((getattr(d, f) for d in data[:n_seeds]), []) for f in ("rgb", "boxes", "positive")))
    validation = Images(*(sum((getattr(d, f) for d in data[n_seeds:]), []) for f in ("rgb", "boxes", "positive")))
    rng = np.random.default_rng(0)
    x, y = windows(training, rng)
    first = fit(x, y)
    x_hard, y_hard = windows(training, rng, HogModel(first.weight, first.bias, -1.0))
    model = fit(np.concatenate([x, x_hard[y_hard == 0]]), np.concatenate([y, y_hard[y_hard == 0]]))
    threshold, scores = peak_f1_threshold(model, validation)
    info = {"scenario": "seed001_room_stream", "train_seeds": [seeds[0], seeds[-1]],
            "validation_seeds": list(VALIDATION_SEEDS), "positives": int(y.sum()), "negatives": int((y == 0).sum()),
            "hard_negatives": int((y_hard == 0).sum()), "svm_c": SVM_C, "validation": scores}
    return HogModel(model.weight, model.bias, threshold), info


def save(model: HogModel, info: dict, out: Path = MODELS_DIR, name: str = MODEL_FILE) -> Path:
    """The model as an .npz of plain arrays with a JSON header, replacing the file whole."""
    path = Path(out) / name
    tmp = path.with_name(f".{path.stem}.{os.getpid()}.partial.npz")
    np.savez_compressed(tmp, header=np.array(json.dumps({"format": MODEL_FORMAT, "info": info})),
                        weight=model.weight, bias=np.array(model.bias), threshold=np.array(model.threshold))
    os.replace(tmp, path)
    return path


def add_arguments(parser) -> None:
    """``train-hog``'s flags."""
    from .training import add_models_out_argument

    parser.add_argument("--camera", choices=("wall", "robot"), default="wall",
                        help="the wall cameras' model (seed 001's room) or the robot depth camera's (seed 003's KTP "
                             "room, training seeds from 5100)")
    parser.add_argument("--seeds", type=int, default=10, help="training seeds, from 4100 (--camera robot: 5100; "
                                                              "default 10)")
    parser.add_argument("--duration", type=float, default=DURATION,
                        help=f"s of each run the images come from (default {DURATION:g})")
    workers.add_arguments(parser)
    add_models_out_argument(parser, "pipeline/detectors/models/")


def main(args) -> int:
    """``crowdsim experiment train-hog``: the wall cameras' model, or with ``--camera robot`` the robot camera's
    (train_hog_robot.py)."""
    import time

    from ..cli import check_duration
    from .training import saved, sizes, training_seeds_out

    check_duration(args)
    robot = args.camera == "robot"
    if robot:
        from pipeline.detectors.hog import ROBOT_MODEL_FILE

        from .train_hog_robot import train as train_model
        out = training_seeds_out(args, 100, 5100)
    else:
        train_model = train
        out = training_seeds_out(args, 100, 4100)
    t0 = time.perf_counter()
    model, info = train_model(args.seeds, Engine(args.workers, args.ray), args.duration)
    name = ROBOT_MODEL_FILE if robot else None
    paths = saved((model, info), lambda m, where: [save(*m, where, *([name] if name else []))], out, MODELS_DIR)
    v = info["validation"]
    print(f"{info['positives']} person windows, {info['negatives']} random and {info['hard_negatives']} hard "
          f"negatives from seeds {info['train_seeds'][0]}-{info['train_seeds'][1]}; ", end="")
    if robot:
        print(f"threshold {model.threshold:.3f} ({info['threshold_recall']:.0%} of the {v['candidates_on_persons']} "
              f"validation candidates on persons pass, {v['false_above_threshold']:.1%} of the "
              f"{v['candidates_on_no_one']} on no one), track start {info['start_confidence']:.3f} "
              f"({info['start_recall']:.0%} pass, {v['false_above_start']:.1%}); ", end="")
    else:
        print(f"validation (IoU 0.5): F1 {v['f1']:.3f}, precision {v['precision']:.3f}, recall {v['recall']:.3f} at "
              f"score {model.threshold:.3f}; ", end="")
    print(f"{time.perf_counter() - t0:.0f} s; model: " + sizes(paths))
    return 0


def add_compare_arguments(parser) -> None:
    """``hog-vs-opencv``'s flags."""
    workers.add_arguments(parser)


def compare_main(args) -> int:
    """``crowdsim experiment hog-vs-opencv``."""
    from ..cli import UsageError

    try:
        import cv2  # noqa: F401
    except ImportError:
        raise UsageError('experiment hog-vs-opencv: needs OpenCV: pip install -e ".[compare]"') from None
    r = compare_opencv(engine=Engine(args.workers, args.ray))
    print(f"HOG person detectors on held-out seeds {r['test_seeds']} ({r['images']} images, "
          f"{r['ours_peak']['persons']} persons), a detection right at IoU 0.5:\n")
    print("| detector | F1 | precision | recall |\n|---|---|---|---|")
    for label, key in (("ours, at its threshold (validation seeds)", "ours_at_threshold"),
                       ("ours, at its best threshold here", "ours_peak"),
                       ("OpenCV's INRIA-trained, at its best threshold here", "opencv_peak")):
        print(f"| {label} | {r[key]['f1']:.3f} | {r[key]['precision']:.3f} | {r[key]['recall']:.3f} |")
    return 0

"""``crowdsim experiment train-hog --camera robot``: the HOG person classifier of seed 003's RGB-D detector
(pipeline/detectors/rgbd.py), trained on the robot's depth camera's rendered colour images and their exact boxes, as
seed 003 trained theirs on INRIA's photographs with Dalal & Triggs's procedure.

Data. The KTP room (``ktp_room``: the robot, its side-mounted 160 x 120 camera) with walkers streaming through it
in both directions, so many differently dressed people pass at 1-5 m. Seeds: training 5100..5100+N-1, validation
5200-5201; seed 003's experiment uses seeds 1-4 (`crowdsim experiment seed003`).

Windows. The classifier scores the box a 3D candidate would hold a person in, from head to ground and half as wide
as high (the detector's ``person_box``), so the windows are such boxes. Positives: each person at least half visible
(KTP's labelling rule) and at least ``MIN_HEIGHT`` pixels tall, the box from the top of their silhouette to their
feet around its middle (parts beyond the image count as empty, as the detector's); the boxes of the detector's own 3D
candidates (its geometry, without HOG) within ``MATCH`` m of such a person on the floor, as the detector will ask
about them (a person's head out of the image, say); and their mirror images. Negatives: the candidates on no one (the
walls' edges, cut by the image), ``NEGATIVES`` random boxes an image, 24 px tall to the image's height, overlapping
no person by more than 0.2; then one round of hard negatives: the best-scored of ``HARD_POOL`` random boxes under the
first model.

Threshold: the score that ``RECALL`` of the validation candidates on persons pass. Seed 003 keeps the HOG threshold
low ("minimum confidences under -1.25 work well, while above this value ... many people are missed", Sec. 4.1.2),
since the 3D stage has already found the candidates; the track-start threshold above it is the score that
``START_RECALL`` of them pass (Table 7's [-1, -0.5], the same role on our scale).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.detectors.hog import HogModel, box_iou, integral, orientation_votes, window_features
from pipeline.detectors.rgbd import RgbdPeopleDetector, person_box
from scenarios import scenario_from_dict
from scenarios.loader import read_raw, resolve
from scenarios.typed import Scenario

from .seeds import map_seeds
from ..workers import Engine
from .train_hog import fit

SCENARIO = "ktp_room"
TRAIN_SEED, VALIDATION_SEEDS = 5100, (5200, 5201)
DURATION, START, EVERY = 60.0, 3.0, 10  # s run, s before the first image kept, camera frames between images kept
MIN_HEIGHT, MIN_VISIBLE = 24, 0.5
MATCH = 0.3  # m on the floor: a candidate on a person (seed 003's 3D match rule)
NEGATIVES, HARD_POOL = 20, 200
RECALL, START_RECALL = 0.97, 0.9


def stream_scenario() -> Scenario:
    """The KTP room with walkers crossing it along and across the camera's view (module docstring)."""
    raw = read_raw(resolve(SCENARIO))
    for key in ("clusters", "sources", "standing"):
        raw.pop(key, None)
    walls = np.concatenate([np.asarray(w, float) for w in raw["map"]["walls"]])
    (x0, y0), (x1, y1) = walls.min(axis=0), walls.max(axis=0)
    corners = {"sw": (x0 + 0.5, y0 + 0.5), "se": (x1 - 0.5, y0 + 0.5), "nw": (x0 + 0.5, y1 - 0.5),
               "ne": (x1 - 0.5, y1 - 0.5)}
    raw["waypoints"] = {name: {"position": list(xy), "radius": 0.4} for name, xy in corners.items()}
    raw["routes"] = {"loop": {"waypoints": ["sw", "ne", "se", "nw"], "sink": False},
                     "back": {"waypoints": ["ne", "sw", "nw", "se"], "sink": False}}
    middle = [(x0 + x1) / 2, (y0 + y1) / 2]
    raw["sources"] = [{"position": middle, "size": [x1 - x0 - 1.0, y1 - y0 - 1.0], "rate": 0.5, "stop": 12.0,
                       "routes": {"loop": 1, "back": 1}}]
    raw["name"] = "ktp_stream"
    return scenario_from_dict(recording(raw), "train-hog robot stream")


def recording(raw: dict) -> dict:
    """A KTP scenario's data set to record its camera: a cycle at each camera frame, no detector (the HOG model's
    training and seed 003's replays run theirs on the frames)."""
    camera = raw["sensors"]["depth_cameras"][0]["name"]
    sensors = [s["name"] for kind in ("lasers", "depth_cameras") for s in raw["sensors"].get(kind, [])]
    raw["pipeline"] = {"cycle": camera, "detectors": {name: None for name in sensors}}
    return raw


@dataclass
class Images:
    """The kept colour images of one seed: per image its boxes, each labelled 1 (a person: a positive), 0 (a 3D
    candidate on no person: a negative) or -1 (a person too little visible: neither, but kept clear of negatives)."""

    rgb: list[np.ndarray]
    boxes: list[np.ndarray]  # the persons' boxes first, then the candidates'
    label: list[np.ndarray]
    persons: list[int]


def collect(seed: int, duration: float = DURATION) -> Images:
    """The kept colour images of a seed's run: the persons' boxes, and the boxes of the detector's 3D candidates,
    a positive when on a person the image shows (within ``MATCH`` m on the floor), else a negative."""
    from crowdsim.loop import Simulation

    sim = Simulation(stream_scenario())
    sim.reset(seed)
    candidates = RgbdPeopleDetector(hog=False)
    out = Images([], [], [], [])
    for k, frame in enumerate(sim.frames(duration)):
        if frame.stamp < START or k % EVERY:
            continue
        for image in frame.depth_frames:
            where, height, _ = candidates.people(image.points)
            truth = truth_boxes(image.full_boxes)
            shown = (image.visible_fraction >= MIN_VISIBLE) & (truth[:, 3] - truth[:, 1] >= MIN_HEIGHT)
            boxes = person_box(image.camera_matrix, where, candidates.ground.plane[:3], height) if len(where) \
                else np.zeros((0, 4))
            gt = frame.groundtruth
            people = gt.position[np.isin(gt.track_id, image.ids[shown])]
            floor = (np.column_stack([where, np.ones(len(where))]) @ image.pose.T)[:, :2]
            on_person = (np.hypot(*(floor[:, None] - people[None]).transpose(2, 0, 1)) < MATCH).any(axis=1) \
                if len(people) else np.zeros(len(where), bool)
            out.rgb.append(image.rgb)
            out.boxes.append(np.concatenate([truth, boxes]))
            out.label.append(np.concatenate([np.where(shown, 1, -1), on_person.astype(int)]))
            out.persons.append(len(truth))
    return out


def truth_boxes(full_boxes: np.ndarray) -> np.ndarray:
    """The person boxes [n, 4] of unoccluded silhouettes: their full height, half as wide, around their middle."""
    b = np.asarray(full_boxes, float).reshape(-1, 4)
    middle, tall = (b[:, 0] + b[:, 2]) / 2, b[:, 3] - b[:, 1]
    return np.column_stack([middle - tall / 4, b[:, 1], middle + tall / 4, b[:, 3]])


def random_boxes(rng: np.random.Generator, w: int, h: int, n: int) -> np.ndarray:
    """``n`` person boxes, 24 px tall to the image's height, centred inside a w x h image."""
    tall = rng.uniform(MIN_HEIGHT, h, n)
    cu, cv = rng.uniform(0, w, n), rng.uniform(0, h, n)
    return np.column_stack([cu - tall / 4, cv - tall / 2, cu + tall / 4, cv + tall / 2])


def windows(data: Images, rng: np.random.Generator, model: HogModel | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Features and labels of the positives (and mirrors), the negative candidates and random boxes of every image;
    with ``model``, its best-scored random boxes (hard negatives) in place of the random ones and candidates."""
    xs, ys = [], []
    for rgb, boxes, label in zip(data.rgb, data.boxes, data.label):
        h, w = rgb.shape[:2]
        table = integral(orientation_votes(rgb))
        pos = boxes[label == 1]
        if len(pos):
            mirror = integral(orientation_votes(rgb[:, ::-1]))
            flipped = np.column_stack([w - pos[:, 2], pos[:, 1], w - pos[:, 0], pos[:, 3]])
            xs += [window_features(table, pos).astype(np.float32), window_features(mirror, flipped).astype(np.float32)]
            ys += [np.ones(2 * len(pos))]
        neg = random_boxes(rng, w, h, NEGATIVES if model is None else HARD_POOL)
        people = boxes[label != 0]
        if len(people):
            neg = neg[box_iou(neg, people).max(axis=1) <= (0.2 if model is None else 0.3)]
        if model is None:
            neg = np.concatenate([boxes[label == 0], neg])
        features = window_features(table, neg).astype(np.float32)
        if model is not None:
            features = features[np.argsort(-(features @ model.weight + model.bias))[:NEGATIVES]]
        xs.append(features)
        ys.append(np.zeros(len(features)))
    return np.concatenate(xs), np.concatenate(ys)


def candidate_scores(model: HogModel, data: Images) -> tuple[np.ndarray, np.ndarray]:
    """The model's scores of the 3D candidates on persons and of those on no one, over the images."""
    on, off = [np.zeros(0)], [np.zeros(0)]
    for rgb, boxes, label, persons in zip(data.rgb, data.boxes, data.label, data.persons):
        if len(boxes) > persons:
            scores = window_features(integral(orientation_votes(rgb)), boxes[persons:]) @ model.weight + model.bias
            on.append(scores[label[persons:] == 1])
            off.append(scores[label[persons:] == 0])
    return np.concatenate(on), np.concatenate(off)


def train(n_seeds: int = 10, engine: Engine = Engine(), duration: float = DURATION) -> tuple[HogModel, dict]:
    seeds = list(range(TRAIN_SEED, TRAIN_SEED + n_seeds))
    data = map_seeds(collect, seeds + list(VALIDATION_SEEDS), duration, engine=engine, desc="train-hog robot")
    fields = ("rgb", "boxes", "label", "persons")
    training = Images(*(sum((getattr(d, f) for d in data[:n_seeds]), []) for f in fields))
    validation = Images(*(sum((getattr(d, f) for d in data[n_seeds:]), []) for f in fields))
    rng = np.random.default_rng(0)
    x, y = windows(training, rng)
    first = fit(x, y)
    x_hard, y_hard = windows(training, rng, first)
    model = fit(np.concatenate([x, x_hard[y_hard == 0]]), np.concatenate([y, y_hard[y_hard == 0]]))
    on, off = candidate_scores(model, validation)
    threshold = float(np.quantile(on, 1 - RECALL))
    start = float(np.quantile(on, 1 - START_RECALL))
    info = {"scenario": "ktp_stream", "camera": "robot", "train_seeds": [seeds[0], seeds[-1]],
            "validation_seeds": list(VALIDATION_SEEDS), "positives": int(y.sum()), "negatives": int((y == 0).sum()),
            "hard_negatives": int((y_hard == 0).sum()), "threshold_recall": RECALL, "start_confidence": start,
            "start_recall": START_RECALL,
            "validation": {"candidates_on_persons": int(len(on)), "candidates_on_no_one": int(len(off)),
                           "false_above_threshold": float(np.mean(off > threshold)) if len(off) else 0.0,
                           "false_above_start": float(np.mean(off > start)) if len(off) else 0.0}}
    return HogModel(model.weight, model.bias, threshold), info

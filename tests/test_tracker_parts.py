"""The NNT built from injected parts (as Stone Soup's trackers are given theirs): a fake part is used as given; the
scenario's nested parts, the old flat keys and the same parts made in Python give the same tracks; a wrong key in a
part, or a part's rule broken, is one error naming the file and the key."""

import numpy as np
import pytest

from pipeline.assemble import TRACKERS, build_part
from pipeline.tracking.association import GlobalNN
from pipeline.tracking.deletion import YoungMatureDeletion
from pipeline.tracking.duplicates import DuplicateGuard
from pipeline.tracking.imm import IMM
from pipeline.tracking.initiation import CountInitiation, ExtendedInitiation
from pipeline.tracking.motion import ConstantVelocity, CoordinatedTurn
from pipeline.tracking.nnt import NearestNeighbourTracker
from scenarios import ScenarioError, load_scenario
from scenarios.format import TRACKER
from scenarios.schema import validate
from test_tracker import dets

DT = 0.04  # 25 Hz


class DeleteAtOnce:
    """A deletion logic that deletes every track, candidates too, in the cycle it is in."""

    def limits(self, confirmed, hits):
        return np.zeros(confirmed.shape, np.int64)


class NeverDelete:
    """A deletion logic that keeps every track for ``after`` misses (for good, by default)."""

    def __init__(self, after: int = 10**9):
        self.after = after

    def limits(self, confirmed, hits):
        return np.full(confirmed.shape, self.after)


def feed(tracker, frames):
    return [tracker.update(f.stamp, f) for f in frames]


def test_an_injected_deletion_logic_is_the_one_used():
    # a person standing at (1, 2) seen every cycle; confirmed at its first detection. The default (fixed) deletion
    # keeps its one track. A logic deleting everything at once: the track of cycle 0 takes the detection of cycle 1
    # and goes, so no track is left; cycle 2's detection starts a new one, and so on.
    frames = [dets(k * DT, [[1.0, 2.0]], first_id=k) for k in range(6)]
    kept = feed(NearestNeighbourTracker(initiation=CountInitiation(1)), frames)
    assert [o.track_id.tolist() for o in kept] == [[1]] * 6
    gone = feed(NearestNeighbourTracker(initiation=CountInitiation(1), deletion=DeleteAtOnce()), frames)
    assert [o.track_id.tolist() for o in gone] == [[1], [], [2], [], [3], []]
    # seen for 5 cycles, then hidden for 50: the default deletes it at the 5th miss, the fake never
    frames = [dets(k * DT, [[1.0, 2.0]] if k < 5 else [], first_id=k) for k in range(55)]
    assert [len(o) for o in feed(NearestNeighbourTracker(), frames)[5:]] == [1] * 4 + [0] * 46
    held = feed(NearestNeighbourTracker(deletion=NeverDelete()), frames)[5:]
    assert all(o.track_id.tolist() == [1] and o.is_occluded.tolist() == [True] for o in held)


def test_a_part_of_ones_own_is_named_in_the_scenario_by_its_class(tmp_path):
    path = tmp_path / "s.yaml"
    path.write_text("base: passers_by\npipeline:\n  tracker:\n    deletion: {type: test_tracker_parts:NeverDelete, "
                    "after: 7}\n")
    spec = load_scenario(str(path))["pipeline"]["tracker"]
    assert spec["deletion"] == {"type": "test_tracker_parts:NeverDelete", "after": 7}
    tracker = build_part(spec, TRACKERS)
    assert type(tracker.deletion) is NeverDelete and tracker.deletion.after == 7


FLAT = {"type": "nnt", "motion": "imm", "imm_models": [{"model": "cv", "process_noise": 0.05},
                                                       {"model": "ct", "process_noise": 0.3, "turn_rate_noise": 0.5}],
        "imm_transition": [0.9, 0.1, 0.2, 0.8], "gate_chi2": 11.0, "association": "global",
        "initiation": "extended", "n_min": 4, "v_max": 2.5, "deletion": "young_mature", "n_delete_young": 6,
        "mature_after": 30, "duplicate_distance": 0.2, "new_track_clearance": 0.3,
        "n_delete": 7, "n_confirm": 2}  # (these two belong to other types of their parts: checked, unused)
NESTED = {"type": "nnt",
          "motion": {"type": "imm", "models": [{"type": "cv", "process_noise": 0.05},
                                               {"type": "ct", "process_noise": 0.3, "turn_rate_noise": 0.5}],
                     "transition": [0.9, 0.1, 0.2, 0.8]},
          "association": {"type": "global", "gate_chi2": 11.0},
          "initiation": {"type": "extended", "n_min": 4, "v_max": 2.5},
          "deletion": {"type": "young_mature", "young": 6, "mature_after": 30},
          "duplicates": {"distance": 0.2, "clearance": 0.3}}


def crossing():
    """Two walkers crossing at right angles (1.2 m/s), one standing, one false alarm every third cycle; the second
    walker unseen for 8 cycles; 100 cycles at 25 Hz, seeded noise of 0.03 m."""
    rng = np.random.default_rng(11)
    frames = []
    for k in range(100):
        t = k * DT
        xy = [[-3.0 + 1.2 * t, 0.0], [0.0, -3.0 + 1.2 * t], [2.0, 2.0]]
        if 40 <= k < 48:
            del xy[1]
        if k % 3 == 0:
            xy.append([rng.uniform(-3, 3), rng.uniform(-3, 3)])
        frames.append(dets(t, np.array(xy) + 0.03 * rng.standard_normal((len(xy), 2)), sigma=0.03,
                           first_id=10 * k))
    return frames


def test_the_nested_and_the_flat_form_and_the_same_parts_in_python_give_the_same_tracks():
    flat, nested = (validate(spec, TRACKER, "<test>", "pipeline.tracker") for spec in (FLAT, NESTED))
    assert flat == nested
    assert validate(nested, TRACKER, "<test>", "pipeline.tracker") == nested  # as a run's scenario.yaml reloads
    in_python = NearestNeighbourTracker(
        motion=IMM([ConstantVelocity(0.05), CoordinatedTurn(0.3, 0.5)], [0.9, 0.1, 0.2, 0.8]),
        association=GlobalNN(11.0), initiation=ExtendedInitiation(n_min=4, v_max=2.5),
        deletion=YoungMatureDeletion(young=6, mature_after=30), duplicates=DuplicateGuard(distance=0.2, clearance=0.3))
    frames = crossing()
    runs = [feed(tracker, frames) for tracker in (build_part(flat, TRACKERS), build_part(nested, TRACKERS), in_python)]
    assert len(np.unique(np.concatenate([o.track_id for o in runs[0]]))) >= 3
    for a, b, c in zip(*runs):
        for name in ("track_id", "is_matched", "detection_id", "position", "velocity", "position_covariance",
                     "velocity_covariance", "age"):
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
            np.testing.assert_array_equal(getattr(a, name), getattr(c, name))


def expect(tmp_path, tracker: str, key: str, *words):
    path = tmp_path / "s.yaml"
    path.write_text(f"base: passers_by\npipeline:\n  tracker: {tracker}\n")
    with pytest.raises(ScenarioError) as info:
        load_scenario(str(path))
    e = info.value
    assert (e.source, e.key) == (str(path), key), str(e)
    assert str(e).startswith(f"{path}: {key}: ")
    for w in words:
        assert w in e.message, (w, e.message)


@pytest.mark.parametrize("tracker, key, words", [
    ("{deletion: {type: young_mature, yung: 20}}", "pipeline.tracker.deletion.yung",
     ["unknown key; expected one of: type, young, mature, mature_after, tentative"]),
    ("{deletion: {type: yung_mature}}", "pipeline.tracker.deletion.type",
     ["expected one of fixed, young_mature or module.path:ClassName", "'yung_mature'"]),
    ("{motion: {type: imm, models: [{type: cv, q: 1.0}]}}", "pipeline.tracker.motion.models[0].q",
     ["unknown key; expected one of: type, process_noise"]),
    ("{initiation: {type: extended, n_min: 1}}", "pipeline.tracker.initiation.n_min", ["at least 2"]),
    ("{duplicates: {must_match: 12}}", "pipeline.tracker.duplicates.must_match", ["at most history (10)"]),
    ("{initiation: {type: base, v_min: 2.5}}", "pipeline.tracker.initiation.v_min", ["expected below v_max (2)"]),
    ("{motion: {type: imm, transition: [0.9, 0.1, 0.1]}}", "pipeline.tracker.motion.transition",
     ["expected the 2 x 2 Markov matrix"]),
    # the old flat keys: the error names the key the file gave
    ("{v_min: 2.5}", "pipeline.tracker.v_min", ["expected below v_max (2)"]),
    ("{n_min: 1}", "pipeline.tracker.n_min", ["at least 2"]),
    ("{association: hungarian}", "pipeline.tracker.association", ["expected one of greedy, global, multi"]),
    ("{motion: imm, imm_transition: [0.9, 0.2, 0.1, 0.9]}", "pipeline.tracker.imm_transition",
     ["each row summing to 1"]),
    ("{motion: imm, imm_transition: [1.0, 0.0, 1.0, 0.0]}", "pipeline.tracker.imm_transition",
     ["each model reachable"]),
    ("{imm_models: [{model: imm, process_noise: 1.0}]}", "pipeline.tracker.imm_models[0].model",
     ["expected one of cv, ca, ct, brownian"]),
    ("{gate_chi2: 9.0, association: {type: greedy, gate_chi2: 10.0}}", "pipeline.tracker.gate_chi2",
     ["the old spelling of pipeline.tracker.association.gate_chi2, which is given too"]),
])
def test_a_wrong_key_or_value_in_a_part_is_one_error_naming_file_and_key(tmp_path, tracker, key, words):
    expect(tmp_path, tracker, key, *words)


def test_a_nested_part_over_a_base_of_old_keys(tmp_path):
    # airport_disembarkation gives the old keys (deletion: young_mature, n_delete_young: 25, n_delete_mature: 48,
    # mature_after: 15): a file on it may name the part anew, and the old keys it does not respell carry over
    path = tmp_path / "s.yaml"
    path.write_text("base: airport_disembarkation\npipeline:\n  tracker:\n    gate_chi2: 9.0\n"
                    "    deletion: {type: young_mature, tentative: 3}\n")
    tracker = load_scenario(str(path))["pipeline"]["tracker"]
    assert tracker["deletion"] == {"type": "young_mature", "young": 25, "mature": 48, "mature_after": 15,
                                   "tentative": 3}
    assert tracker["association"] == {"type": "greedy", "gate_chi2": 9.0}
    # one it respells is given twice: one error, which says how to drop the base's
    path.write_text("base: airport_disembarkation\npipeline:\n  tracker:\n"
                    "    deletion: {type: young_mature, mature: 60}\n")
    with pytest.raises(ScenarioError, match="n_delete_mature: !remove") as info:
        load_scenario(str(path))
    assert info.value.key == "pipeline.tracker.n_delete_mature"
    path.write_text("base: airport_disembarkation\npipeline:\n  tracker:\n    n_delete_mature: !remove\n"
                    "    deletion: {type: young_mature, mature: 60}\n")
    assert load_scenario(str(path))["pipeline"]["tracker"]["deletion"]["mature"] == 60

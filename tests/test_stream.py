"""Streaming evaluation: the same figures, bit for bit, however the frames are chunked, from memory or from CSV files
read a few rows at a time; state that grows with persons and tracks, never with frames; and one clear error for a
file that cannot be streamed."""

import math

import numpy as np
import pytest

from evaluation import ClearMot, Sequence
from evaluation.hota import Hota
from evaluation.io import EvaluationInputError, load_sequence, sequence_chunks
from evaluation.ospa import Ospa, ospa
from evaluation.score import score_tracking
from evaluation.stream import CsvPair, SequencePair, aligned
from evaluation.tables import Counts, ExactSum, Slots


def run_like(seed: int, frames: int = 60, persons: int = 12):
    """Persons walking in and out of view (ignored rows), tracks that follow with noise, switch ids, miss rows and
    add false positives, and a gap of frames without rows."""
    rng = np.random.default_rng(seed)
    pos = rng.uniform(0, 8, (persons, 2))
    track_of = np.arange(persons) + 100
    g, t = [], []
    for f in [*range(frames // 2), *range(frames // 2 + 3, frames)]:
        pos += rng.normal(0, 0.05, pos.shape)
        alive = rng.random(persons) < 0.9
        for i in np.flatnonzero(alive):
            g.append((f, i + 1, *pos[i], rng.random() < 0.15))
        if rng.random() < 0.1:
            track_of[rng.integers(persons)] = track_of.max() + 1
        for i in np.flatnonzero(alive & (rng.random(persons) < 0.85)):
            t.append((f, track_of[i], *(pos[i] + rng.normal(0, 0.3, 2))))
        t.append((f, -1 - f % 3, *rng.uniform(0, 8, 2)))  # a false positive
    g, t = np.array(g), np.array(t)
    return (Sequence.from_rows(g[:, 0], g[:, 1], g[:, 2:4], 0.04 * g[:, 0], g[:, 4] > 0),
            Sequence.from_rows(t[:, 0], t[:, 1], t[:, 2:4], 0.04 * t[:, 0]))


def write_run(folder, gt, tracks):
    """The sequences as a run writes them (rows within a frame in any order)."""
    paths = folder / "groundtruth.csv", folder / "tracks.csv"
    rng = np.random.default_rng(0)
    for path, seq, gt_file in ((paths[0], gt, True), (paths[1], tracks, False)):
        rows = np.column_stack([seq.frame, seq.stamp, seq.id, seq.position] + ([~seq.ignore] if gt_file else []))
        rows = rows[np.lexsort((rng.random(len(rows)), rows[:, 0]))]  # shuffled within each frame
        header = "frame,t,id,x,y" + (",visible" if gt_file else "")
        np.savetxt(path, rows, fmt=["%d", "%.2f", "%d", "%.4f", "%.4f"] + (["%d"] if gt_file else []),
                   delimiter=",", header=header, comments="")
    return paths


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_chunks_of_any_size_give_the_same_figures_bit_for_bit(seed):
    gt, tracks = run_like(seed)
    whole = score_tracking(SequencePair(gt, tracks))
    assert whole["id_switches"] > 0 and whole["gt"] > 0 and whole["fragmentations"] > 0  # a telling case
    for frames in (1, 2, 7, 25):
        assert score_tracking(SequencePair(gt, tracks, chunk_frames=frames)) == whole


def test_files_read_a_few_rows_at_a_time_give_what_the_whole_files_give(tmp_path):
    gt, tracks = run_like(3)
    gt_path, tracks_path = write_run(tmp_path, gt, tracks)
    whole = score_tracking(SequencePair(load_sequence(gt_path), load_sequence(tracks_path, occlusion=False)))
    for rows in (1, 5, 17, 1000):
        pair = CsvPair(gt_path, tracks_path, chunk_rows=rows)
        assert score_tracking(pair) == whole
        assert (pair.gt_rows, pair.gt_ignored, pair.first_frame) == (len(gt), int(gt.ignore.sum()), 0)
    # a chunk cut inside a frame holds its rows back: every chunk is whole frames, sorted by frame and id
    chunks = list(sequence_chunks(gt_path, chunk_rows=5))
    joined = Sequence.join(chunks)
    np.testing.assert_array_equal(joined.frame, gt.frame)
    np.testing.assert_array_equal(joined.id, gt.id)
    assert all(len(set(c.frame) & set(d.frame)) == 0 for c, d in zip(chunks, chunks[1:]))


def test_aligned_chunks_cover_the_same_frames_on_both_sides():
    def seq(frames):
        return Sequence.from_rows(frames, np.arange(len(frames)), np.zeros((len(frames), 2)))

    gt_chunks = [seq([0, 0, 1]), seq([2, 5]), seq([6])]
    track_chunks = [seq([1, 2, 3]), seq([4, 9])]
    got = [(g.frame.tolist(), t.frame.tolist()) for g, t in aligned(gt_chunks, track_chunks)]
    # frames are given out once both sides are complete up to them: the first gt chunk ends at 1, the first track
    # chunk at 3, and so on; the gt side is done after 6, so 9 goes out alone
    assert got == [([0, 0, 1], [1]), ([2], [2, 3]), ([5], [4]), ([6], []), ([], [9])]


def test_state_grows_with_persons_and_tracks_not_with_frames():
    def sizes(frames):
        # the same three persons and tracks in every frame, for ``frames`` frames
        f = np.repeat(np.arange(frames), 3)
        ids = np.tile([1, 2, 3], frames)
        xy = np.tile([[0.0, 0.0], [3.0, 0.0], [6.0, 0.0]], (frames, 1))
        gt, tracks = Sequence.from_rows(f, ids, xy), Sequence.from_rows(f, ids + 10, xy + 0.1)
        cm, h, o = ClearMot(), Hota(), Ospa()
        for frame in range(frames):
            cm.update(ids[:3], xy[:3], ids[:3] + 10, xy[:3] + 0.1)
        assert cm.result().mt == 3
        h.add(gt, tracks)
        o.add(gt, tracks)
        return (len(cm._persons), len(cm._pairs), len(h.gt_ids), len(h.pairs), len(o.together),
                o.sums["ospa"].count, len(o.sums["ospa"].partials) <= 2)

    short, long = sizes(10), sizes(1000)
    assert short[:5] == long[:5] == (3, 3, 3, 3, 9)  # every pair of a person and a track shares frames in OSPA
    assert (short[5], long[5]) == (10, 1000) and short[6] and long[6]


def test_exact_sum_is_the_correctly_rounded_sum_in_any_order():
    rng = np.random.default_rng(5)
    values = np.concatenate([rng.normal(0, 1, 1000), [1e16, 1.0, -1e16]])
    for order in (np.arange(len(values)), rng.permutation(len(values))):
        s = ExactSum()
        for part in np.array_split(values[order], 7):
            s.add(part)
        assert s.total == math.fsum(values) and s.count == len(values)
    assert ExactSum().mean() is None


def test_counts_kept_in_segments_are_the_counts_of_all_keys_at_once():
    rng = np.random.default_rng(3)
    batches = [rng.integers(0, 5000, rng.integers(0, 300)) for _ in range(60)]
    counts = Counts(segment=16)
    for batch in batches:
        counts.add(batch)
    keys, n = np.unique(np.concatenate(batches), return_counts=True)
    assert len(counts) == len(keys) and len(counts.keys) > 20  # split into many segments
    assert max(len(k) for k in counts.keys) <= 32
    assert np.array_equal(np.concatenate(counts.keys), keys)
    assert np.array_equal(np.concatenate(counts.counts), n)


def test_ospa_counts_the_pairs_together_the_same_on_its_grid_and_by_sorting(monkeypatch):
    import evaluation.ospa

    gt, tracks = run_like(4, frames=80, persons=15)
    gt = gt.select(~gt.ignore)
    on_grid = ospa(gt, tracks)
    monkeypatch.setattr(evaluation.ospa, "_GRID_CELLS", 0)  # every chunk too large for the grid
    assert ospa(gt, tracks) == on_grid and on_grid["labelled_tracks"] > 5


def test_slots_are_dense_in_order_of_first_appearance():
    slots = Slots()
    assert slots(np.array([50, 7, 50])).tolist() == [1, 0, 1]  # new keys of one call in ascending order
    assert slots(np.array([-3, 7, 9])).tolist() == [2, 0, 3]
    assert slots(np.array([8, 9]), add=False).tolist() == [-1, 3]
    assert slots.keys.tolist() == [7, 50, -3, 9]


def test_blank_lines_anywhere_are_skipped(tmp_path):
    path = tmp_path / "gt.csv"
    path.write_text("frame,id,x,y\n0,1,0,0\n\n\n\n\n0,2,1,0\n\n\n\n\n1,1,0,0\n\n")
    for rows in (1, 2, 3, 100):
        chunks = list(sequence_chunks(path, chunk_rows=rows))
        assert [(c.frame.tolist(), c.id.tolist()) for c in chunks] == [([0, 0], [1, 2]), ([1], [1])]


def test_a_file_out_of_frame_order_gets_one_clear_error(tmp_path):
    path = tmp_path / "gt.csv"
    path.write_text("frame,id,x,y\n0,1,0,0\n2,1,0,0\n1,1,0,0\n")
    for rows in (2, 100):  # across a chunk boundary and within a chunk
        with pytest.raises(EvaluationInputError, match=r"gt.csv: frame 1 comes after frame 2; expected rows sorted"):
            list(sequence_chunks(path, chunk_rows=rows))
    path.write_text("frame,id,x,y\n0,1,0,0\n1,1,0,0\n1,2,0,0\n1,1,5,5\n")
    with pytest.raises(EvaluationInputError, match="id 1 appears twice in frame 1"):  # split over two chunks
        list(sequence_chunks(path, chunk_rows=2))


def test_exact_sum_by_hand():
    # 0.1 ten times is 1.0 exactly rounded (a running sum gives 0.9999999999999999); 1e16 + 1 - 1e16 keeps the 1
    s = ExactSum()
    s.add([0.1] * 10)
    assert s.total == 1.0 and sum([0.1] * 10) != 1.0
    s.add([1e16, 1.0, -1e16])
    assert s.total == 2.0 and s.count == 13 and s.mean() == 2.0 / 13

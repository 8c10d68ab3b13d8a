"""evaluation/metric.py: CLEAR-MOT, HOTA and OSPA share one protocol, chunks of whole frames in, a result out."""

import json

import numpy as np
from test_stream import run_like

from evaluation.clearmot import ClearMot, ClearMotResult
from evaluation.hota import Hota, HotaResult
from evaluation.metric import accumulate
from evaluation.ospa import Ospa, OspaResult


def chunked(gt, tracks, cuts):
    """(gt, tracks) chunks of whole frames, cut before the given frame numbers."""
    edges = [-np.inf, *cuts, np.inf]
    return [(gt.select((gt.frame >= a) & (gt.frame < b)), tracks.select((tracks.frame >= a) & (tracks.frame < b)))
            for a, b in zip(edges[:-1], edges[1:])]


def test_every_metric_gives_the_same_result_however_the_frames_are_cut():
    gt, tracks = run_like(2)
    counted = gt.select(~gt.ignore)
    whole = [ClearMot(), Hota(), Ospa()]
    accumulate(whole[:1], [(gt, tracks)])
    accumulate(whole[1:], [(counted, tracks)])
    cut = [ClearMot(), Hota(), Ospa()]
    accumulate(cut[:1], chunked(gt, tracks, [7, 8, 40]))
    accumulate(cut[1:], chunked(counted, tracks, [7, 8, 40]))
    for a, b, kind in zip(whole, cut, (ClearMotResult, HotaResult, OspaResult)):
        assert isinstance(a.result(), kind) and a.result() == b.result()
        assert json.loads(json.dumps(a.result().as_dict(), allow_nan=False)) == a.result().as_dict()
    assert [m.passes for m in whole] == [1, 2, 2]

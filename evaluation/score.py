"""The tracking object of metrics.json, and its table: one function scores any tracker's output, ours in the loop's
run and anyone's through ``crowdsim evaluate``, so the two agree exactly.

It streams: the ground truth and the tracks come as aligned chunks of whole frames (evaluation/stream.py), read
twice, and every metric keeps state per person, track or pair of them, never per frame, so a run of any length is
scored in constant memory.
"""

from __future__ import annotations

import numpy as np

from .clearmot import ClearMot, ClearMotResult
from .heap import release_memory
from .hota import Hota, HotaResult
from .ospa import Ospa, OspaResult

OSPA_CUTOFF, OSPA_ORDER = 1.0, 1.0  # m; the c = 1 m, p = 1 (SPENCER's online_analysis uses the same)


def counted_chunks(frames, threshold: float, matched=None):
    """The chunks of ``frames`` (aligned (gt, tracks) Sequences) as HOTA and OSPA see them: the ground truth not
    ignored, and the tracks but those CLEAR-MOT matched to an ignored person (which are no false positives there
    either); and the ClearMot that decided it, filled once the iteration ends. ``matched``: called with each chunk's
    ground truth and its frames' (frame, FrameResult), CLEAR-MOT's matching for another metric (the groups')."""
    cm = ClearMot(threshold)

    def chunks():
        for gt, tracks in frames:
            results = list(cm.scored_frames(gt, tracks))
            if matched is not None:
                matched(gt, results)
            excused = [(np.full(len(r.excused_hyp_ids), frame), r.excused_hyp_ids)
                       for frame, r in results if len(r.excused_hyp_ids)]
            keep = np.ones(len(tracks), bool)
            if excused:
                ids = np.unique(tracks.id)
                key = tracks.frame * len(ids) + np.searchsorted(ids, tracks.id)
                frame, excused_ids = (np.concatenate(parts) for parts in zip(*excused))
                keep = ~np.isin(key, frame * len(ids) + np.searchsorted(ids, excused_ids))
            yield gt.select(~gt.ignore), tracks.select(keep)

    return chunks(), cm


def score_tracking(frames, threshold: float = 1.0, matched=None) -> dict:
    """CLEAR-MOT, rIDS, MT/PT/ML, fragmentations, the id swap split and IDF1 of the tracks against the ground truth
    of ``frames`` (re-iterable aligned chunks: ``stream.CsvPair`` or ``stream.SequencePair``); then HOTA and OSPA on
    what counts (``counted_chunks``): metrics.json's tracking object. Two passes over ``frames``: HOTA's alignment
    and OSPA-T's labels are global (evaluation/metric.py). ``matched``: as ``counted_chunks`` takes it, called in
    the first pass only (``group_score.GroupScore.add``: the group metrics on the same reading and matching)."""
    h, o = Hota(), Ospa(OSPA_CUTOFF, OSPA_ORDER)
    chunks, cm = counted_chunks(frames, threshold, matched)
    for gt, tracks in chunks:
        h.add(gt, tracks)
        o.add(gt, tracks)
    clearmot = cm.result()
    release_memory()  # what the first pass's chunks left in the heap, before the labelling's arrays
    h.next_pass()
    o.next_pass()
    release_memory()
    for gt, tracks in counted_chunks(frames, threshold)[0]:
        h.add(gt, tracks)
        o.add(gt, tracks)
    return tracking_json(clearmot, h.result(), o.result())


def tracking_json(clearmot: ClearMotResult, hota: HotaResult, ospa: OspaResult) -> dict:
    """metrics.json's tracking object: CLEAR-MOT's figures, then HOTA's and OSPA's under their names there."""
    per_alpha = hota.per_alpha
    return {**clearmot.as_dict(), "hota": hota.hota, "deta": hota.deta, "assa": hota.assa, "loca": hota.loca,
            "ospa_m": ospa.ospa, "ospa_localisation_m": ospa.localisation, "ospa_cardinality_m": ospa.cardinality,
            "ospa_t_m": ospa.ospa_t,
            "hota_per_alpha": {"alpha": per_alpha.alpha, "hota": per_alpha.hota, "deta": per_alpha.deta,
                               "assa": per_alpha.assa, "loca": per_alpha.loca}}


def pct(v) -> str:
    """A share as a percentage with one decimal, n/a when undefined."""
    return "n/a" if v is None else f"{100 * v:.1f}%"


def tracking_table(tracking: dict, extra: dict[str, str] | None = None) -> str:
    """A Markdown table of the figures the seeds report (seed 000 Table II: MOTA, MOTP, FP%, miss%, IDS, rIDS, MT,
    ML), IDF1, the counts, and any ``extra`` columns."""
    motp = "n/a" if tracking["motp_m"] is None else f"{tracking['motp_m']:.3f} m"
    rids = "n/a" if tracking["rids"] is None else f"{tracking['rids']:.0f}"
    cells = {"MOTA": pct(tracking["mota"]), "MOTP": motp, "FP%": pct(tracking["fp_rate"]),
             "miss%": pct(tracking["miss_rate"]), "IDS": str(tracking["id_switches"]), "rIDS": rids,
             "MT": str(tracking["mt"]), "ML": str(tracking["ml"]), "IDF1": pct(tracking["idf1"]),
             "HOTA": pct(tracking.get("hota")),
             "FP": str(tracking["fp"]), "FN": str(tracking["fn"]), "GT": str(tracking["gt"]), **(extra or {})}
    return "\n".join(["| " + " | ".join(cells) + " |", "|" + "---|" * len(cells),
                      "| " + " | ".join(cells.values()) + " |"])


# (label, key, scale, format) of the columns of the seeds' tables
SEED000_COLUMNS = (("MOTA [%]", "mota", 100, ".1f"), ("MOTP [m]", "motp_m", 1, ".3f"),
                   ("FP [%]", "fp_rate", 100, ".1f"), ("miss [%]", "miss_rate", 100, ".1f"),
                   ("IDS", "id_switches", 1, ".1f"), ("rIDS", "rids", 1, ".0f"),
                   ("MT", "mt", 1, ".1f"), ("ML", "ml", 1, ".1f"), ("IDF1 [%]", "idf1", 100, ".1f"),
                   ("HOTA [%]", "hota", 100, ".1f"), ("OSPA [m]", "ospa_m", 1, ".3f"))
SEED001_COLUMNS = (("TSR", "tsr", 1, ".3f"), ("MR", "miss_rate", 1, ".3f"), ("GR", "fp_rate", 1, ".3f"),
                   ("mismatch", "id_switches", 1, ".2f"), ("id swaps", "id_swaps", 1, ".2f"),
                   ("MOTP [cm]", "motp_m", 100, ".2f"), ("MOTA", "mota", 1, ".3f"))


def mean_sd(results: list[dict]) -> tuple[dict, dict]:
    """Each figure's mean and sample standard deviation (n - 1; None for one run) over repeated runs, as seed 001
    reports its eight runs per sequence; figures undefined in a run (None) are left out of its mean."""
    mean, sd = {}, {}
    for key in results[0] if results else ():
        values = [r[key] for r in results if isinstance(r.get(key), (int, float)) and not isinstance(r[key], bool)]
        if values:
            mean[key] = float(np.mean(values))
            sd[key] = float(np.std(values, ddof=1)) if len(values) > 1 else None
    return mean, sd


def seeds_table(results: list[dict], columns=SEED001_COLUMNS) -> str:
    """A Markdown table of the given columns as the seeds print them: the value of one run, or mean and sd."""
    mean, sd = mean_sd(results)

    def cell(key, scale, fmt, of):
        v = of.get(key)
        return "n/a" if v is None else format(scale * v, fmt)

    head = [label for label, *_ in columns]
    row = [cell(key, scale, fmt, mean) for _, key, scale, fmt in columns]
    if len(results) < 2:
        return "\n".join(["| " + " | ".join(head) + " |", "|" + "---|" * len(head), "| " + " | ".join(row) + " |"])
    spread = [cell(key, scale, fmt, sd) for _, key, scale, fmt in columns]
    return "\n".join(["| | " + " | ".join(head) + " |", "|" + "---|" * (len(head) + 1),
                      f"| mean of {len(results)} | " + " | ".join(row) + " |", "| sd | " + " | ".join(spread) + " |"])

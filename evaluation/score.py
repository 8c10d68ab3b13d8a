"""The tracking object of metrics.json, and its table: one function scores any tracker's output, ours in the loop's
run and anyone's through ``crowdsim evaluate``, so the two agree exactly."""

from __future__ import annotations

from .clearmot import evaluate
from .sequence import Sequence


def score_tracking(gt: Sequence, tracks: Sequence, threshold: float = 1.0) -> dict:
    """CLEAR-MOT, rIDS, MT/PT/ML, fragmentations, the id swap split and IDF1 of ``tracks`` against ``gt``."""
    return evaluate(gt, tracks, threshold)


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
             "FP": str(tracking["fp"]), "FN": str(tracking["fn"]), "GT": str(tracking["gt"]), **(extra or {})}
    return "\n".join(["| " + " | ".join(cells) + " |", "|" + "---|" * len(cells),
                      "| " + " | ".join(cells.values()) + " |"])

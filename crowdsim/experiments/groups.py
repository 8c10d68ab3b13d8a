"""``crowdsim experiment groups``: the group stage on held-out airport seeds, with each relation classifier (ours,
``svm`` and ``forest``, against SPENCER's released model), each linkage and a range of thresholds, from the tracker's
tracks and from the true persons themselves (what a perfect tracker would give: the difference is what the tracker
costs the group stage).

Besides the group metrics (evaluation/groups.py), the queue check: in each cycle, the largest number of strangers
(persons of different true groups, a person alone their own) that one detected group joins among the persons
standing in the passport queues. SPENCER's single linkage chains a queue whose neighbours stand 0.7 m apart into one
group (``pipeline/groups/detection.py``).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from evaluation.groups import GroupFrame, GroupMetrics
from pipeline.groups import LINKAGES, CoherentMotionGroups
from pipeline.types import TrackedGroups

from .relations import DURATION, HELD_OUT_SEED, SCENARIO, GroupCycle, collect
from .seeds import map_seeds
from .. import workers
from ..workers import Engine

MODELS = ("svm", "forest", "spencer")
THRESHOLDS = (0.3, 0.4, 0.5, 0.6, 0.7, 0.8)
SOURCES = ("tracker", "groundtruth")
QUEUE_CHAIN = 3  # strangers in one detected group that make a queue chain


def strangers_joined(cycle: GroupCycle, groups: TrackedGroups) -> int:
    """The most strangers among the queued persons that one detected group holds (0 without such a group)."""
    queued = set(cycle.gt.track_id[cycle.queued].tolist())
    person = dict(zip(cycle.matched_track.tolist(), cycle.matched_gt.tolist()))
    identity = dict(zip(cycle.gt.track_id.tolist(),
                        np.where(cycle.gt.group_id >= 0, cycle.gt.group_id, -1 - cycle.gt.track_id).tolist()))
    best = 0
    for g in groups.group_id.tolist():
        members = [person.get(t) for t in groups.member_track[groups.member_group == g].tolist()]
        best = max(best, len({identity[p] for p in members if p in queued}))
    return best


def score(cycles: list[GroupCycle], source: str, model: str, linkage: str, threshold: float) -> dict:
    """The group metrics of one configuration over one run, with the relation curves and the queue check."""
    stage = CoherentMotionGroups(model=model, threshold=threshold, linkage=linkage)
    metrics = GroupMetrics(relation_threshold=threshold)
    chains, largest = 0, []
    for c in cycles:
        c = c.from_groundtruth() if source == "groundtruth" else c
        relations, groups = stage.update(c.stamp, c.tracks)
        metrics.update(GroupFrame(c.gt.track_id, c.gt.group_id, c.gt.position, c.matched_gt, c.matched_track,
                                  c.excused, relations.track_a, relations.track_b, relations.strength,
                                  groups.member_group, groups.member_track))
        if c.queued.sum() >= QUEUE_CHAIN:
            joined = strangers_joined(c, groups)
            chains += joined >= QUEUE_CHAIN
            largest.append(joined)
    curves = {k: v.tolist() for k, v in metrics.curves(101).items()}
    return {**metrics.summary(), "curves": curves,
            "queue": {"cycles": len(largest), "chained": chains, "mean_largest": float(np.mean(largest)) if largest
                      else None}}


def configurations():
    """(source, model, linkage, threshold) of every configuration scored."""
    return [(s, m, k, t) for s in SOURCES for m in MODELS for k in LINKAGES for t in THRESHOLDS]


def one_seed(seed: int, duration: float = DURATION) -> list[dict]:
    cycles = collect(seed, duration)
    return [score(cycles, *config) for config in configurations()]


def run(seeds: list[int], duration: float = DURATION, engine: Engine = Engine(), progress: bool = True) -> list[list[dict]]:
    """[seed][configuration] results."""
    return map_seeds(one_seed, seeds, duration, engine=engine, desc="groups", progress=progress)


def pooled(results: list[list[dict]], k: int, path: tuple[str, ...]) -> float | None:
    """The mean over seeds of one figure (``path`` into a summary) of configuration ``k``; None if undefined
    in every seed."""
    values = []
    for per_seed in results:
        v = per_seed[k]
        for key in path:
            v = v[key]
        if v is not None:
            values.append(v)
    return float(np.mean(values)) if values else None


def _cell(v, percent=True) -> str:
    return "n/a" if v is None else f"{100 * v:.1f}" if percent else f"{v:.3f}"


def report(results: list[list[dict]], seeds: list[int]) -> str:
    configs = configurations()
    index = {c: k for k, c in enumerate(configs)}
    lines = [f"Groups on {SCENARIO}, held-out seeds {seeds[0]}..{seeds[-1]} ({len(seeds)} runs); figures are means "
             "over the runs, in %", "",
             "Relations (pairs of tracks matched to persons within 3 m; related at strength >= 0.5):", "",
             "| tracks | model | pairs | related | precision | recall | F1 | AUC | Brier |",
             "|---|---|---|---|---|---|---|---|---|"]
    for source in SOURCES:
        for model in MODELS:
            k = index[(source, model, "single", 0.5)]
            p = ("pairwise",)
            lines.append(f"| {source} | {model} | {pooled(results, k, p + ('pairs',)):.0f} | "
                         f"{pooled(results, k, p + ('positives',)):.0f} | "
                         + " | ".join(_cell(pooled(results, k, p + (key,))) for key in ("precision", "recall", "f1"))
                         + f" | {_cell(pooled(results, k, p + ('auc',)), False)} | "
                           f"{_cell(pooled(results, k, p + ('brier',)), False)} |")
    lines += ["", "Groups at threshold 0.5 (F1 of Setti et al. at T = 2/3 and 1, G-MITRE F1, group MOTA, group ID "
                  f"switches per run; queue: share of cycles with {QUEUE_CHAIN}+ queueing strangers in one group):", "",
              "| tracks | model | linkage | F1 T=2/3 | F1 T=1 | G-MITRE F1 | group MOTA | group IDS | queue chains |",
              "|---|---|---|---|---|---|---|---|---|"]
    for source in SOURCES:
        for model in MODELS:
            for linkage in LINKAGES:
                k = index[(source, model, linkage, 0.5)]
                queue = [r[k]["queue"] for r in results]
                share = sum(q["chained"] for q in queue) / max(sum(q["cycles"] for q in queue), 1)
                lines.append(f"| {source} | {model} | {linkage} | " + " | ".join(
                    _cell(pooled(results, k, path)) for path in (("t_2_3", "f1"), ("t_1", "f1"), ("gmitre", "f1"),
                                                                 ("tracking", "mota")))
                             + f" | {pooled(results, k, ('tracking', 'id_switches')):.1f} | {100 * share:.1f} |")
    lines += ["", "Best threshold for group F1 at T = 2/3, per model and linkage (tracker tracks):", "",
              "| model | linkage | threshold | F1 T=2/3 |", "|---|---|---|---|"]
    for model in MODELS:
        for linkage in LINKAGES:
            f1 = [pooled(results, index[("tracker", model, linkage, t)], ("t_2_3", "f1")) or 0.0 for t in THRESHOLDS]
            best = int(np.argmax(f1))
            lines.append(f"| {model} | {linkage} | {THRESHOLDS[best]:g} | {100 * f1[best]:.1f} |")
    return "\n".join(lines)


def _mean_curve(curves: list) -> np.ndarray:
    """The runs' curves averaged at each threshold, over the runs where the point is defined (precision is not
    where no pair reaches the threshold): NaN where none is."""
    values = np.array(curves, float)
    defined = np.isfinite(values)
    count = defined.sum(axis=0)
    return np.where(count > 0, np.where(defined, values, 0.0).sum(axis=0) / np.maximum(count, 1), np.nan)


def plot(results: list[list[dict]], path) -> None:
    """ROC and precision-recall curves of each classifier (tracker solid, true persons dashed; averaged over the
    runs at each threshold), and group F1 at T = 2/3 against the threshold."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    configs = configurations()
    index = {c: k for k, c in enumerate(configs)}
    fig, axes = plt.subplots(1, 3, figsize=(16, 5))
    colours = dict(zip(MODELS, ("tab:blue", "tab:green", "tab:red")))
    for source, style in zip(SOURCES, ("-", "--")):
        for model in MODELS:
            k = index[(source, model, "single", 0.5)]
            fpr, tpr, precision, recall = (_mean_curve([r[k]["curves"][key] for r in results])
                                           for key in ("fpr", "tpr", "precision", "recall"))
            label = f"{model}, {source}"
            axes[0].plot(fpr, tpr, style, color=colours[model], label=label)
            axes[1].plot(recall, precision, style, color=colours[model], label=label)
            for linkage, marker in zip(LINKAGES, ("o", "s", "^")):
                if source == "tracker" or linkage == "single":
                    f1 = [pooled(results, index[(source, model, linkage, t)], ("t_2_3", "f1")) for t in THRESHOLDS]
                    axes[2].plot(THRESHOLDS, [np.nan if v is None else 100 * v for v in f1], style, marker=marker,
                                 color=colours[model], label=f"{model}, {linkage}, {source}")
    axes[0].set(xlabel="false positive rate", ylabel="true positive rate", title="relations: ROC")
    axes[1].set(xlabel="recall", ylabel="precision", title="relations: precision-recall")
    axes[2].set(xlabel="relation threshold", ylabel="group F1 at T = 2/3 (%)", title="groups: F1 against threshold")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def write(out: Path, results: list[list[dict]], seeds: list[int]) -> str:
    """groups.md, groups.json (every seed's figures per configuration) and groups.png into ``out``."""
    text = report(results, seeds)
    (out / "groups.md").write_text(text + "\n")
    configs = configurations()
    (out / "groups.json").write_text(json.dumps({
        "scenario": SCENARIO, "seeds": seeds,
        "configurations": [{"tracks": s, "model": m, "linkage": k, "threshold": t,
                            "runs": [{key: v for key, v in r[i].items() if key != "curves"} for r in results]}
                           for i, (s, m, k, t) in enumerate(configs)]}, indent=1) + "\n")
    plot(results, out / "groups.png")
    return text


def held_out_seeds(n: int) -> list[int]:
    return list(range(HELD_OUT_SEED, HELD_OUT_SEED + n))


def add_arguments(parser) -> None:
    from ..cli import add_out_argument

    parser.add_argument("--seeds", type=int, default=5, help=f"held-out seeds, from {HELD_OUT_SEED} (default 5)")
    parser.add_argument("--duration", type=float, default=DURATION,
                        help=f"s of each airport run (default {DURATION:g})")
    workers.add_arguments(parser)
    add_out_argument(parser, "groups")


def main(args) -> int:
    """``crowdsim experiment groups``."""
    from ..cli import UsageError, check_duration, run_dir
    from ..outdir import write_directory

    if args.seeds < 1 or args.workers < 1:
        raise UsageError(f"--seeds and --workers: expected at least 1, got {args.seeds} and {args.workers}")
    check_duration(args)
    seeds = held_out_seeds(args.seeds)
    out = run_dir(args, "groups")
    results = run(seeds, args.duration, engine=Engine(args.workers, args.ray))
    print(write_directory(out, lambda tmp: write(tmp, results, seeds)))
    print(f"\n{out / 'groups.md'}, groups.json, groups.png")
    return 0

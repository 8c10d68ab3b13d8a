"""``crowdsim experiment table2``: seed 000's Table II (tracker ablation) on our airport, beside the published PedSim
column, and its claims checked one by one.

The trackers see what seed 000's saw: the same fused laser detections, recorded once per seed from the airport run
(its lasers, map filter, fusion and route; the tracker does not steer the robot) with seed 000's detector, the boosted
segment classifier ("we used the same boosted 2D laser segment classifier" for every row, Sec. IV-C: our
``laser_learned`` AdaBoost), then replayed into each row's tracker, as seed 000 replayed its recorded data. Scoring
is seed 000's: CLEAR-MOT at 1 m, persons within 20 m, the occluded ignored (the airport's ``evaluation`` section).
Cycles/s is the tracker's own update time, as the seed's last column ("without taking the detection stage into
account").

Each row is scored twice: over every person (the seed's evaluation), and over the walking persons alone (persons
slower than the initiation logic's v_min = 0.2 m/s ignored as the occluded are). Half of our airport's counted
persons stand (queues, static groups, waiting passengers); the seed's PedSim sequence is "very dynamic", and the
initiation logic's velocity gate is there not to start tracks on standing persons (Sec. V-B). The second table shows
which of the claims turn on that difference.
"""

from __future__ import annotations

import numpy as np

from pipeline.assemble import TRACKERS, build_part
from scenarios import load_scenario
from scenarios.typed import Scenario, plain
from scenarios.format import DETECTOR as DETECTOR_SPEC
from scenarios.format import TRACKER
from scenarios.schema import validate

from .recorded import Cycle, detect, record, track
from .seeds import map_seeds
from .. import workers
from ..workers import Engine

SCENARIO = "airport_disembarkation"
DETECTOR = {"type": "laser_learned", "model": "adaboost"}  # seed 000 Sec. IV-C: the boosted segment classifier
WALKING = 0.2  # m/s, the initiation logic's v_min (seed 000 Sec. V-B): slower persons are left out of "walking"
EVALUATIONS = ("all", "walking")

# Table II's rows: (label, the tracker's keys, seed 000's PedSim column: MOTA %, ID switches, FP %, miss %, Hz).
# The keys name the parts as pipeline/tracking does; what a row leaves out is the base NNT's (n_del = 5), and every
# NNT row has the SPENCER NNT's guards against duplicate tracks, which its code runs in every configuration
# (pipeline/tracking/duplicates.py).
BASE = {"type": "nnt", "n_delete": 5, "duplicate_distance": 0.15, "new_track_clearance": 0.25}
DELETION = {"deletion": "young_mature"}
ROWS = [
    ("Global NN", {**BASE, "association": "global"}, (80.4, 4962, 12.4, 5.7, 1323)),
    ("Greedy NN, multi-association", {**BASE, "association": "multi"}, (78.8, 5627, 14.1, 5.5, 1403)),
    ("Greedy NN", {**BASE}, (80.5, 4968, 12.4, 5.7, 1061)),
    ("+Extended initiation logic", {**BASE, "initiation": "extended"}, (78.9, 3112, 4.9, 15.3, 1260)),
    ("+Deletion logic", {**BASE, **DELETION}, (71.1, 1842, 25.0, 3.3, 747)),
    ("+Base initiation logic", {**BASE, **DELETION, "initiation": "base"}, (80.8, 1234, 9.1, 9.6, 1025)),
    ("+Extended initiation logic ", {**BASE, **DELETION, "initiation": "extended"}, (82.2, 1315, 9.4, 7.9, 935)),
    ("+IMM (CV + CV)", {**BASE, **DELETION, "initiation": "extended", "motion": "imm"},
     (82.2, 1272, 9.4, 8.0, 606)),
    ("MHT t_max = 0.03 s", {"type": "mht"}, (71.3, 3670, 23.0, 4.8, 32)),
]
COLUMNS = ("mota", "ids", "fp", "miss", "hz")


def seed000_pipeline(scenario: Scenario) -> dict:
    """The airport's pipeline section with seed 000's detector in place of its own."""
    return {**plain(scenario.pipeline), "detector": validate(DETECTOR, DETECTOR_SPEC, "<table2>", "pipeline.detector")}


def replay(cycles: list[Cycle], detections: list, spec: dict) -> dict:
    """A tracker of ``spec`` over recorded detections: per evaluation (``EVALUATIONS``), MOTA, ID switches, FP % and
    miss % (of the counted ground truth), and the tracker's cycles/s."""
    tracker = build_part(validate(spec, TRACKER, "<table2>", "pipeline.tracker"), TRACKERS)
    summaries, hz = track(cycles, detections, tracker, 1.0, {"all": 0.0, "walking": WALKING})
    return {name: {"mota": 100 * s.mota, "ids": s.id_switches, "fp": 100 * s.fp_rate, "miss": 100 * s.miss_rate,
                   "hz": hz} for name, s in summaries.items()}


def _one_seed(seed: int, duration: float | None) -> list[dict]:
    scenario = load_scenario(SCENARIO)
    cycles = record(scenario, seed, duration)
    detections = detect(cycles, seed000_pipeline(scenario), scenario.map)
    return [replay(cycles, detections, spec) for _, spec, _ in ROWS]


def table2(seeds: list[int], duration: float | None = None, engine: Engine = Engine(),
           progress: bool = True) -> dict[str, np.ndarray]:
    """Per evaluation (``EVALUATIONS``), [rows, seeds, columns] of figures."""
    out = map_seeds(_one_seed, seeds, duration, engine=engine, desc="table2", progress=progress)
    return {name: np.array([[[r[name][c] for c in COLUMNS] for r in rows] for rows in out]).transpose(1, 0, 2)
            for name in EVALUATIONS}


def claims(mean: np.ndarray) -> list[tuple[str, bool, str]]:
    """Table II's claims (a)-(h) on the mean figures: (claim, holds, the numbers that decide it)."""
    row = {label.strip(): k for k, (label, _, _) in enumerate(ROWS)}
    ext_alone, ext_full = 3, 6  # the two "+Extended initiation logic" rows: alone, and with deletion
    g, gl, mu = mean[row["Greedy NN"]], mean[row["Global NN"]], mean[row["Greedy NN, multi-association"]]
    ini, dele, base = mean[ext_alone], mean[row["+Deletion logic"]], mean[row["+Base initiation logic"]]
    full, imm, mht = mean[ext_full], mean[row["+IMM (CV + CV)"]], mean[row["MHT t_max = 0.03 s"]]
    m, i, fp, miss, hz = range(5)
    return [(text, bool(ok), numbers) for text, ok, numbers in [
        ("(a) global NN within 1 point of greedy NN's MOTA", abs(gl[m] - g[m]) <= 1,
         f"{gl[m]:.1f} vs {g[m]:.1f}"),
        ("(b) multi-association has more ID switches than greedy", mu[i] > g[i], f"{mu[i]:.0f} vs {g[i]:.0f}"),
        ("(c) initiation alone cuts FP% by 40% or more and raises miss%", ini[fp] <= 0.6 * g[fp] and ini[miss] > g[miss],
         f"FP {ini[fp]:.1f} vs {g[fp]:.1f}, miss {ini[miss]:.1f} vs {g[miss]:.1f}"),
        ("(d) deletion alone raises FP% and cuts ID switches", dele[fp] > g[fp] and dele[i] < g[i],
         f"FP {dele[fp]:.1f} vs {g[fp]:.1f}, IDS {dele[i]:.0f} vs {g[i]:.0f}"),
        ("(e) initiation with deletion: at most half of greedy's ID switches, MOTA no lower",
         base[i] <= 0.5 * g[i] and base[m] >= g[m], f"IDS {base[i]:.0f} vs {g[i]:.0f}, MOTA {base[m]:.1f} vs {g[m]:.1f}"),
        ("(f) extended initiation at least base initiation's MOTA", full[m] >= base[m],
         f"{full[m]:.1f} vs {base[m]:.1f}"),
        ("(g) the IMM changes MOTA by under 1 point, ID switches not raised", abs(imm[m] - full[m]) < 1 and imm[i] <= full[i],
         f"MOTA {imm[m]:.1f} vs {full[m]:.1f}, IDS {imm[i]:.0f} vs {full[i]:.0f}"),
        ("(h) the MHT scores below the full NNT and runs 10x slower or more",
         mht[m] < full[m] and mht[hz] * 10 <= full[hz], f"MOTA {mht[m]:.1f} vs {full[m]:.1f}, "
                                                         f"{mht[hz]:.0f} vs {full[hz]:.0f} cycles/s"),
    ]]


def report(figures: dict[str, np.ndarray], seeds: list[int]) -> str:
    """Per evaluation, the table (mean and sd over the seeds beside the published PedSim figures) and the claims."""
    lines = [f"Table II on {SCENARIO}, seeds {seeds[0]}..{seeds[-1]}, detector laser_learned (AdaBoost)"]
    for name in EVALUATIONS:
        fig = figures[name]
        mean = fig.mean(axis=1)
        sd = fig.std(axis=1, ddof=1) if fig.shape[1] > 1 else 0 * mean
        lines += ["", f"{'Every person' if name == 'all' else f'Walking persons only (below {WALKING} m/s ignored)'}"
                      " (mean +- sd; seed 000's PedSim column after /)", "",
                  "| method | MOTA % | ID switches | FP % | miss % | cycles/s |", "|---|---|---|---|---|---|"]
        for k, (label, _, paper) in enumerate(ROWS):
            cells = [f"{mean[k, c]:.1f} +- {sd[k, c]:.1f} / {paper[c]:g}" if c not in (1, 4) else
                     f"{mean[k, c]:.0f} +- {sd[k, c]:.0f} / {paper[c]:g}" for c in range(5)]
            lines.append(f"| {label.strip()} | " + " | ".join(cells) + " |")
        lines += ["", "Claims:"] + [f"- {'holds' if ok else 'DOES NOT HOLD'}: {text} ({numbers})"
                                    for text, ok, numbers in claims(mean)]
    return "\n".join(lines)


def plot(figures: dict[str, np.ndarray], path) -> None:
    """MOTA and ID switches of each row, ours (mean and sd, both evaluations) beside the published PedSim column."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels = [label.strip() for label, _, _ in ROWS]
    y = np.arange(len(ROWS))
    fig, axes = plt.subplots(1, 2, figsize=(12, 5), sharey=True)
    greedy = labels.index("Greedy NN")
    for ax, c, title in zip(axes, (0, 1), ("MOTA %", "ID switches / greedy NN's (the sequences differ in length)")):
        paper = np.array([row[2][c] for row in ROWS], float)
        ours = {name: figures[name][:, :, c] for name in EVALUATIONS}
        if c == 1:
            paper = paper / paper[greedy]
            ours = {name: v / v[greedy].mean() for name, v in ours.items()}
        ax.barh(y - 0.27, paper, 0.26, color="0.7", label="seed 000, PedSim")
        for k, (name, colour) in enumerate(zip(EVALUATIONS, ("tab:blue", "tab:orange"))):
            ax.barh(y + 0.27 * k, ours[name].mean(axis=1), 0.26, xerr=ours[name].std(axis=1), color=colour,
                    label=f"ours, {'every person' if name == 'all' else 'walking persons'}")
        ax.set_title(title)
        ax.grid(axis="x", alpha=0.3)
    axes[0].set_yticks(y, labels)
    axes[0].invert_yaxis()
    handles, names = axes[0].get_legend_handles_labels()
    fig.legend(handles, names, loc="lower center", ncol=3, fontsize=9)
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    fig.savefig(path, dpi=110)
    plt.close(fig)


def write(out, figures: dict[str, np.ndarray], seeds: list[int]) -> str:
    """Write table2.md, table2.json (every seed's figures) and table2.png into ``out``; returns the report."""
    import json
    from pathlib import Path

    out = Path(out)
    text = report(figures, seeds)
    (out / "table2.md").write_text(text + "\n")
    (out / "table2.json").write_text(json.dumps({
        "scenario": SCENARIO, "seeds": seeds, "detector": DETECTOR, "columns": list(COLUMNS),
        "rows": [{"label": label.strip(), "tracker": spec, "published_pedsim": list(paper),
                  **{name: figures[name][k].tolist() for name in EVALUATIONS}}
                 for k, (label, spec, paper) in enumerate(ROWS)]}, indent=1) + "\n")
    plot(figures, out / "table2.png")
    return text


def add_arguments(parser) -> None:
    from ..cli import add_out_argument

    parser.add_argument("--seeds", type=int, default=20, help="seeds from 1 (default 20)")
    parser.add_argument("--duration", type=float, help="s of each airport run (default: the scenario's)")
    workers.add_arguments(parser)
    add_out_argument(parser, "table2")


def main(args) -> int:
    """``crowdsim experiment table2``."""
    from ..cli import UsageError, check_duration, run_dir
    from ..outdir import write_directory

    if args.seeds < 1:
        raise UsageError(f"--seeds: expected at least 1, got {args.seeds}")
    check_duration(args)
    seeds = list(range(1, args.seeds + 1))
    out = run_dir(args, "table2")
    figures = table2(seeds, args.duration, engine=Engine(args.workers, args.ray))
    print(write_directory(out, lambda tmp: write(tmp, figures, seeds)))
    print(f"\n{out / 'table2.md'}, table2.json, table2.png")
    return 0

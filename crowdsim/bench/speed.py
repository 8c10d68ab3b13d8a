"""``crowdsim bench speed [--against DIR]``: the loop's, the crowd's and the environments' speed figures, and, side by
side in the same run, the same figures of the code in DIR (a checkout of an older commit: ``git worktree add DIR
COMMIT`` makes one).

Each figure is measured by ``probe.py`` in a fresh process per tree and round, the trees alternately and their order
swapped each round, so that both see the same machine; times are CPU times (the machine is shared), but for the end
to end run, whose wall time is the figure. The medians over the rounds are printed, with ours over theirs.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
from tqdm import tqdm

from .common import write_figures
from .probe import FIGURES

OURS = str(Path(__file__).resolve().parents[2])  # the folder holding this tree's packages
PROBE = str(Path(__file__).with_name("probe.py"))


def add_arguments(parser) -> None:
    parser.add_argument("--against", metavar="DIR", help="also measure the code in DIR (a checkout holding crowdsim/, "
                                                         "pipeline/, ...), side by side")
    parser.add_argument("--rounds", type=int, default=3, help="measurements per figure and tree (default 3)")
    parser.add_argument("--figures", nargs="+", choices=FIGURES, default=list(FIGURES), help="the figures to measure")
    parser.add_argument("--json", help="also write every measurement to this JSON file")
    parser.add_argument("--quick", action="store_true", help="shorter measurements (for a smoke test)")


def measure(tree: str, figure: str, quick: bool) -> dict:
    """One figure of the tree ``tree``, from a process of its own."""
    done = subprocess.run([sys.executable, PROBE, tree, figure, *(["--quick"] if quick else [])], capture_output=True,
                          text=True)
    if done.returncode:
        raise RuntimeError(f"the {figure} figure of {tree} failed:\n{done.stderr[-3000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def run_speed(trees: dict[str, str], figures: list[str], rounds: int, quick: bool) -> dict:
    """{tree label: {figure: {key: [value per round]}}}, the trees measured alternately."""
    samples = {label: {f: {} for f in figures} for label in trees}
    jobs = [(r, f, label) for r in range(rounds) for f in figures
            for label in (list(trees) if r % 2 == 0 else list(trees)[::-1])]
    for r, figure, label in tqdm(jobs, desc="bench speed", unit="figure"):
        for key, value in measure(trees[label], figure, quick).items():
            samples[label][figure].setdefault(key, []).append(value)
    return samples


def table(samples: dict) -> list[str]:
    labels = list(samples)
    lines = [f"{'figure':34s}" + "".join(f"{label:>14s}" for label in labels)
             + ("        ours/theirs" if len(labels) == 2 else "")]
    for figure, keys in samples[labels[0]].items():
        for key in keys:
            medians = [float(np.median(samples[label][figure][key])) for label in labels]
            ratio = f"{medians[0] / medians[1]:17.2f}x" if len(labels) == 2 else ""
            lines.append(f"{figure + ' ' + key:34s}" + "".join(f"{m:14,.2f}" for m in medians) + ratio)
    return lines


def main(args) -> int:
    from ..cli import UsageError, check_json

    check_json(args)
    if args.rounds < 1:
        raise UsageError(f"--rounds {args.rounds}: expected at least 1")
    trees = {"ours": OURS}
    if args.against is not None:
        against = Path(args.against).resolve()
        if not (against / "crowdsim" / "loop.py").is_file():
            raise UsageError(f"--against {args.against}: expected a checkout of crowdsim (DIR/crowdsim/loop.py)")
        trees["theirs"] = str(against)
    samples = run_speed(trees, args.figures, args.rounds, args.quick)
    print("\n".join(table(samples)))
    write_figures(args.json, {"trees": trees, "rounds": args.rounds, "quick": args.quick, "samples": samples})
    return 0

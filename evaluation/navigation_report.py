"""``crowdsim evaluate-nav``: the navigation metrics of run directories as tables, one row per run plus mean and
sample standard deviation over the runs (as seed 001 reports its repeated runs), and optionally as JSON.

A figure's mean and sd are over the runs where it is finite: NaN is undefined there (time to goal of a failed run,
the following figures of a goal task), inf is "never" (no one on a collision course); the outcome flags average to
rates. In the JSON, NaN and inf are null (NaN and inf are not JSON): for min_time_to_collision null means inf.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from .io import EvaluationInputError
from .navigation import navigation_metrics, read_nav_run

# (label, key, scale, format) of the two tables' columns
OUTCOME_COLUMNS = (("success [%]", "success", 100, ".0f"), ("coll. person [%]", "collision_person", 100, ".0f"),
                   ("coll. wall [%]", "collision_wall", 100, ".0f"), ("timeout [%]", "timeout", 100, ".0f"),
                   ("ended early [%]", "ended_early", 100, ".0f"), ("time to goal [s]", "time_to_goal", 1, ".2f"),
                   ("path [m]", "path_length", 1, ".2f"), ("irregularity [rad/m]", "path_irregularity", 1, ".3f"),
                   ("mean acc. [m/s^2]", "mean_linear_acceleration", 1, ".3f"),
                   ("peak jerk [m/s^3]", "peak_linear_jerk", 1, ".2f"),
                   ("mean ang. acc. [rad/s^2]", "mean_angular_acceleration", 1, ".3f"),
                   ("peak ang. jerk [rad/s^3]", "peak_angular_jerk", 1, ".2f"))
SOCIAL_COLUMNS = (("min dist. [m]", "min_distance", 1, ".3f"), ("discomfort [%]", "discomfort_frequency", 100, ".1f"),
                  ("intimate [%]", "intimate_share", 100, ".1f"), ("personal [%]", "personal_share", 100, ".1f"),
                  ("min TTC [s]", "min_time_to_collision", 1, ".2f"), ("social work [m/s]", "social_work", 1, ".2f"),
                  ("cross front", "crossings_front", 1, ".2f"), ("cross behind", "crossings_behind", 1, ".2f"),
                  ("dist. error [m]", "distance_error", 1, ".3f"), ("in band [%]", "in_band_share", 100, ".1f"),
                  ("losses", "target_losses", 1, ".2f"), ("reacq. mean [s]", "mean_reacquire_time", 1, ".2f"),
                  ("reacq. max [s]", "max_reacquire_time", 1, ".2f"), ("hidden [%]", "target_hidden_share", 100, ".1f"))


def mean_sd(runs: list[dict]) -> tuple[dict, dict]:
    """Each figure's mean and sample sd (n - 1) over the runs where it is finite; NaN where none is (sd: fewer
    than two)."""
    mean, sd = {}, {}
    for key in runs[0]:
        v = np.array([float(r[key]) for r in runs])
        v = v[np.isfinite(v)]
        mean[key] = float(v.mean()) if v.size else float("nan")
        sd[key] = float(v.std(ddof=1)) if v.size > 1 else float("nan")
    return mean, sd


def _cell(value, scale, fmt) -> str:
    value = float(value)
    return "n/a" if math.isnan(value) else "inf" if math.isinf(value) else format(scale * value, fmt)


def nav_table(names: list[str], runs: list[dict], columns) -> str:
    """A Markdown table of ``columns``: a row per run, then mean and sd."""
    mean, sd = mean_sd(runs)
    rows = [(name, run) for name, run in zip(names, runs)] + [(f"mean of {len(runs)}", mean), ("sd", sd)]
    lines = ["| run | " + " | ".join(label for label, *_ in columns) + " |", "|" + "---|" * (len(columns) + 1)]
    lines += [f"| {name} | " + " | ".join(_cell(of[key], scale, fmt) for _, key, scale, fmt in columns) + " |"
              for name, of in rows]
    return "\n".join(lines)


def json_safe(value):
    """``value`` (figures, a scenario: dicts and lists of them) with NaN and inf as None, JSON's null: strict JSON,
    which every parser reads."""
    if isinstance(value, dict):
        return {k: json_safe(v) for k, v in value.items()}
    if isinstance(value, list):
        return [json_safe(v) for v in value]
    return None if isinstance(value, float) and not math.isfinite(value) else value


def evaluate_nav_main(run_dirs: list[Path], json_path: Path | None) -> str:
    """The navigation metrics of each run directory (``read_nav_run``) as two tables (outcome, path and
    smoothness; social, passers-by and following); with ``json_path`` (a new file) also {"runs": [...], "mean":
    ..., "sd": ...}, each run with its "run_dir"."""
    if json_path is not None and Path(json_path).exists():
        raise EvaluationInputError(f"--json {json_path}: already exists; expected a new file (nothing was written)")
    if not run_dirs:
        raise EvaluationInputError("expected at least one run directory")
    runs = [navigation_metrics(read_nav_run(d)) for d in run_dirs]
    names = [Path(d).name or str(d) for d in run_dirs]
    if json_path is not None:
        mean, sd = mean_sd(runs)
        Path(json_path).write_text(json.dumps({"runs": [{"run_dir": str(d), **json_safe(r)}
                                                        for d, r in zip(run_dirs, runs)],
                                               "mean": json_safe(mean), "sd": json_safe(sd)}, indent=2) + "\n")
    return "\n".join([f"{len(runs)} run(s): outcome, path and smoothness", "", nav_table(names, runs, OUTCOME_COLUMNS),
                      "", "social, passers-by and following", "", nav_table(names, runs, SOCIAL_COLUMNS)])

"""``crowdsim navigate``: one planner over a fixed suite of seeds of a navigation scenario, scored in memory.

Each seed is one episode: the scenario (its robot driven to its goals or following its target) with the planner
named on the command line, the crowd's warm-up, then the frames up to the last goal or the duration. The episode
is built from the frames as a ``NavEpisode`` (the robot's true pose, every person alive, the walls, the task; for
following, the follower's track of the target and whether the robot's sensors saw it) and scored by
``evaluation.navigation.navigation_metrics``, the figures ``crowdsim evaluate-nav`` gives for a run directory: the
numbers ``crowdsim run`` writes (at full precision) and ``read_nav_run`` reads back, in the same order, and the task
through the same navigation.json spec, so a run of the same seed gets the same figures to the last bit. No run
directory is written. Seeds S..S+N-1 are the suite, so two planners meet the same crowds; every seed starts over
from ``Simulation.reset(seed)``, so its figures do not depend on the workers or the order.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
from tqdm import tqdm

from evaluation.io import EvaluationInputError
from evaluation.navigation import NavEpisode, PersonRows, navigation_metrics, navigation_task
from evaluation.navigation_report import OUTCOME_COLUMNS, SOCIAL_COLUMNS, json_safe, mean_sd, nav_table
from scenarios import ScenarioError
from scenarios.format import PLANNER
from scenarios.schema import validate
from scenarios.typed import Scenario, plain

from .loop import Simulation
from .run import navigation_spec
from .workers import Engine, process_pool, run_all

# the columns of the table: (label, key, scale, format), as evaluate-nav's
GOAL_COLUMNS = ("success", "time_to_goal", "path_length", "path_irregularity", "min_distance",
                "discomfort_frequency", "intimate_share", "personal_share", "min_time_to_collision", "social_work",
                "crossings_front", "crossings_behind", "mean_linear_acceleration", "peak_linear_jerk")
FOLLOW_COLUMNS = ("success", "in_band_share", "distance_error", "target_losses", "mean_reacquire_time",
                  "target_hidden_share", "path_length", "min_distance", "discomfort_frequency", "intimate_share",
                  "personal_share", "min_time_to_collision", "crossings_front", "crossings_behind")


def with_planner(scenario: Scenario, planner: str | None) -> Scenario:
    """The scenario with ``robot.planner`` of type ``planner``: its own parameters when it names that type
    already (or ``planner`` is None), the type's defaults otherwise. A scenario whose robot drives its route has no
    planner to change: ScenarioError naming robot.driver."""
    robot = scenario.robot
    if robot.driver not in ("goals", "follow"):
        raise ScenarioError(scenario.source, "robot.driver",
                            f"{robot.driver} (the robot drives its {robot.driver}, no planner); expected goals "
                            "or follow: crowdsim navigate compares planners on a scenario whose robot drives to "
                            "goals or follows a person")
    if planner in (None, robot.planner.type):
        return scenario
    return scenario.replace(robot=robot.replace(planner=validate({"type": planner}, PLANNER, "--planner",
                                                                 "robot.planner")))


def episode_metrics(sim: Simulation, seed: int, duration: float) -> dict:
    """One episode at ``seed``: warm-up, then the frames up to the last goal or ``duration``, scored."""
    sim.reset(seed)
    sim.warm_up()
    stamp, pose, follow = [], [], []
    frame_of, ids, position, velocity, radius = [], [], [], [], []
    # what crowdsim run writes to robot.csv, persons.csv and following.csv (at full precision: the same numbers),
    # in the same order
    for frame in sim.frames(duration):
        a = frame.agents
        frame_of.append(np.full(len(a.id), len(stamp)))
        ids.append(a.id)
        position.append(a.position)
        velocity.append(a.velocity)
        radius.append(a.radius)
        stamp.append(frame.stamp)
        pose.append(frame.robot_pose)
        follow.append((frame.target_track, frame.target_visible))
    persons = PersonRows(np.concatenate(frame_of), np.concatenate(ids), np.concatenate(position),
                         np.concatenate(velocity), np.concatenate(radius))
    # the task as crowdsim run writes it to navigation.json and read_nav_run takes it from there
    task = navigation_task(navigation_spec(sim.scenario.replace(duration=duration), sim.target_id),
                           f"{sim.scenario.source}: the navigation task")
    following = {}
    if task["task"] == "follow":
        track, visible = np.array(follow).T
        following = {"target_track": track, "target_visible": visible.astype(bool)}
    return navigation_metrics(NavEpisode(stamp=np.array(stamp), robot_pose=np.array(pose), persons=persons, **task,
                                         **following))


_worker: dict = {}


def _start_worker(scenario: Scenario, duration: float) -> None:
    _worker["sim"], _worker["duration"] = Simulation(scenario), duration


def _run_seed(seed: int) -> dict:
    return episode_metrics(_worker["sim"], seed, _worker["duration"])


def _episode(seed: int, scenario: Scenario, duration: float) -> dict:
    """One episode in a simulation of its own (a Ray task)."""
    return episode_metrics(Simulation(scenario), seed, duration)


def navigate(scenario: Scenario, seeds: list[int], duration: float, workers: int = 1, progress: bool = True,
             ray: str | None = None) -> list[dict]:
    """The navigation figures of each seed's episode, in the order of ``seeds``; over ``workers`` processes (each
    with a simulation of its own) when more than one, or as Ray tasks at ``ray`` (crowdsim/workers.py)."""
    desc = f"{scenario.name} / {scenario.robot.planner.type}"
    if ray is not None:
        return run_all(_episode, seeds, scenario, duration, engine=Engine(workers, ray), desc=desc, unit="seed",
                       progress=progress)
    bar = tqdm(total=len(seeds), unit="seed", disable=not progress, desc=desc)
    try:
        if workers <= 1:
            sim = Simulation(scenario)
            runs = []
            for seed in seeds:
                runs.append(episode_metrics(sim, seed, duration))
                bar.update()
            return runs
        with process_pool(workers, _start_worker, (scenario, duration)) as pool:
            runs = []
            for figures in pool.map(_run_seed, seeds):
                runs.append(figures)
                bar.update()
            return runs
    finally:
        bar.close()


def counts(runs: list[dict]) -> dict:
    """How many episodes ended in success, a collision (with a person, a wall), a timeout or early."""
    total = {key: sum(bool(r[key]) for r in runs) for key in ("success", "collision_person", "collision_wall",
                                                              "timeout", "ended_early")}
    return {"episodes": len(runs), "successes": total["success"],
            "collisions": total["collision_person"] + total["collision_wall"],
            "collisions_person": total["collision_person"], "collisions_wall": total["collision_wall"],
            "timeouts": total["timeout"], "ended_early": total["ended_early"]}


def summary(runs: list[dict], task: str) -> str:
    """The counts, and the mean and sample sd over the episodes of the figures that matter for the task."""
    columns = {c[1]: c for c in OUTCOME_COLUMNS + SOCIAL_COLUMNS}
    chosen = [columns[key] for key in (GOAL_COLUMNS if task == "goal" else FOLLOW_COLUMNS)]
    table = nav_table([""] * len(runs), runs, chosen).splitlines()
    mean_row, sd_row = table[-2], table[-1]
    c = counts(runs)
    line = (f"{c['successes']}/{c['episodes']} successes, {c['collisions']} collisions ({c['collisions_person']} "
            f"with a person, {c['collisions_wall']} with a wall), {c['timeouts']} timeouts, {c['ended_early']} ended "
            f"early")
    return "\n".join([line, "", *table[:2], mean_row, sd_row])


def navigate_main(scenario: Scenario, planner: str | None, first_seed: int, n_seeds: int, duration: float | None,
                  json_path: Path | None, workers: int = 1, progress: bool = True, ray: str | None = None) -> str:
    """``crowdsim navigate``: the table (and, with ``json_path``, a new file with every episode's figures)."""
    if json_path is not None and Path(json_path).exists():
        raise EvaluationInputError(f"--json {json_path}: already exists; expected a new file (nothing was run)")
    if n_seeds < 1:
        raise EvaluationInputError(f"--seeds: expected at least 1 episode, got {n_seeds}")
    if workers < 1:
        raise EvaluationInputError(f"--workers: expected at least 1 process, got {workers}")
    if duration is not None and not (math.isfinite(duration) and duration > 0):
        raise EvaluationInputError(f"--duration: expected a time above 0 s, got {duration}")
    if first_seed < 0:
        raise EvaluationInputError(f"--first-seed: expected a seed of at least 0, got {first_seed}")
    scenario = with_planner(scenario, planner)
    duration = scenario.duration if duration is None else float(duration)
    seeds = list(range(first_seed, first_seed + n_seeds))
    runs = navigate(scenario, seeds, duration, workers, progress, ray)
    task = "goal" if scenario.robot.driver == "goals" else "follow"
    if json_path is not None:
        mean, sd = mean_sd(runs)
        Path(json_path).write_text(json.dumps({
            "scenario": scenario.name, "planner": plain(scenario.robot.planner), "task": task,
            "duration_s": duration, "seeds": seeds, "counts": counts(runs),
            "runs": [{"seed": seed, **json_safe(r)} for seed, r in zip(seeds, runs)],
            "mean": json_safe(mean), "sd": json_safe(sd)}, indent=2) + "\n")
    head = (f"{scenario.name}, planner {scenario.robot.planner.type}, seeds {seeds[0]}..{seeds[-1]}, "
            f"{duration:g} s each: mean and sd over the {len(runs)} episodes")
    return head + "\n\n" + summary(runs, task)

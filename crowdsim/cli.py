"""The ``crowdsim`` command: run, evaluate, evaluate-nav, navigate, report, scenarios, validate-scenario, validate,
scenario-keys, bench, experiment, dataset."""

from __future__ import annotations

import argparse
import errno
import math
import re
import sys
import time
import warnings
from dataclasses import dataclass
from importlib import import_module
from pathlib import Path

from .errors import Error


class UsageError(Error):
    """A command-line argument that cannot be used: one line naming it and what was expected."""


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """Warnings as one line naming what they concern (a PedSim file's element and line), not our source line."""
    print(f"crowdsim: warning: {message}", file=sys.stderr if file is None else file)


def _load(args, name: str, **flags):
    """The scenario ``name`` with the command's flags over its keys (``flags``: key -> its value, None: the file's);
    a flag's bad value is blamed on the flag, not on the file."""
    from scenarios import ScenarioError, load_scenario

    try:
        return load_scenario(name, allow_large=getattr(args, "allow_large", False), **flags)
    except ScenarioError as e:
        if flags.get(e.key) is not None:
            raise UsageError(f"--{e.key} {flags[e.key]}: {e.message}") from None
        raise


def _cmd_run(args) -> int:
    from .run import cameras_line, navigation_tables, run, summary_table

    scenario = _load(args, args.scenario, seed=args.seed, duration=args.duration)
    out = run_dir(args, scenario.name)
    metrics = run(scenario, out, rrd=args.rrd, progress=not args.quiet)
    print(summary_table(metrics))
    if "navigation" in metrics:
        print(f"\nnavigation ({'goal' if scenario.robot.driver == 'goals' else 'following'}, "
              f"{metrics['duration_s']:.1f} s recorded):\n")
        print(navigation_tables(metrics["navigation"]))
        print()
    gt = metrics["groundtruth"]
    print(f"persons within range: {gt['mean_persons_in_range']:.1f} mean, {gt['max_persons_in_range']} max; "
          f"results in {out}/")
    if metrics["cameras"]:
        print(cameras_line(metrics))
    return 0


GROUP_FILES = ("relations.csv", "groups.csv")


def _cmd_evaluate(args) -> int:
    import json

    from evaluation.group_score import GroupScore, groups_table
    from evaluation.io import EvaluationInputError, write_motchallenge
    from evaluation.score import (SEED000_COLUMNS, SEED001_COLUMNS, mean_sd, score_tracking, seeds_table,
                                  tracking_table)
    from evaluation.stream import CsvPair

    from .outdir import check_out_dir, write_directory, write_file

    check_json(args)
    if args.motchallenge is not None:
        check_out_dir(args.motchallenge, "--motchallenge")  # as given: "" is refused, not ignored
    if args.visible_column is not None and not args.visible_column.strip():
        raise UsageError("--visible-column: empty; expected the name of the ground truth's visibility column")
    if not (math.isfinite(args.threshold) and args.threshold > 0):
        raise UsageError(f"--threshold {args.threshold}: expected a distance above 0 m")
    if args.max_range is not None and not (args.max_range > 0):  # inf: no limit
        raise UsageError(f"--max-range {args.max_range}: expected a distance above 0 m")
    if bool(args.runs) == bool(args.gt or args.tracks) or (not args.runs and not (args.gt and args.tracks)):
        raise EvaluationInputError("expected either --gt GT.csv and --tracks TRACKS.csv, or --runs DIR [DIR ...]")
    if bool(args.relations) != bool(args.groups) or (args.runs and args.relations):
        raise EvaluationInputError("--relations and --groups: expected both, with --gt and --tracks (--runs scores "
                                   "the groups of each run directory that has relations.csv and groups.csv)")

    def files(gt_path, tracks_path, groups: bool = False) -> CsvPair:
        return CsvPair(gt_path, tracks_path, occlusion=not args.no_occlusion, visible_column=args.visible_column,
                       max_range=args.max_range, groups=groups)

    def scores(pair: CsvPair, relations_path=None, groups_path=None) -> tuple[dict, dict | None]:
        """The tracking scores of ``pair``, and with the two group files their group scores, in one reading."""
        group_score = GroupScore(relations_path, groups_path) if relations_path else None
        tracking = score_tracking(pair, args.threshold, group_score and group_score.add)
        return tracking, group_score and group_score.result()

    if args.runs:
        if args.motchallenge is not None:
            raise EvaluationInputError("--motchallenge exports one pair of files: give --gt and --tracks")
        # every file scored before anything is printed: a bad one is the one line printed
        with_groups = [Path(d) for d in args.runs if all((Path(d) / f).is_file() for f in GROUP_FILES)]
        scored = [scores(files(d / "groundtruth.csv", d / "tracks.csv", True), *(d / f for f in GROUP_FILES))
                  if d in with_groups else scores(files(d / "groundtruth.csv", d / "tracks.csv"))
                  for d in map(Path, args.runs)]
        runs = [tracking for tracking, _ in scored]
        groups = [g for _, g in scored if g is not None]
        print(f"{len(runs)} runs at {args.threshold:g} m, mean and sample standard deviation")
        print(seeds_table(runs, SEED000_COLUMNS))
        print()
        print(seeds_table(runs, SEED001_COLUMNS))
        mean, sd = mean_sd(runs)
        report = {"runs": runs, "mean": mean, "sd": sd}
        if with_groups:
            print(f"\ngroups of the {len(groups)} runs with {' and '.join(GROUP_FILES)}, one row each")
            for d, g in zip(with_groups, groups):
                print(f"{d}:\n{groups_table(g)}")
            report["groups"] = {str(d): g for d, g in zip(with_groups, groups)}
        if args.json:
            write_file(Path(args.json), json.dumps(report, indent=2) + "\n")
        return 0
    pair = files(args.gt, args.tracks, bool(args.relations))
    # scored before anything is printed: a bad file is the one line printed
    tracking, groups = scores(pair, args.relations, args.groups)
    report = {"tracking": tracking}
    if groups is not None:
        report["groups"] = groups
    print(tracking_table(tracking))
    print(f"{tracking['frames']} frames; {pair.gt_ignored} ground-truth rows ignored (occluded or out of range); "
          f"threshold {args.threshold:g} m")
    if args.relations:
        print()
        print(groups_table(report["groups"]))
    if args.json:
        write_file(Path(args.json), json.dumps(report, indent=2) + "\n")
    if args.motchallenge is not None:
        first = pair.first_frame or 0

        def motchallenge(tmp: Path) -> None:
            write_motchallenge(tmp / "gt.txt", pair.gt_chunks(), groundtruth=True, first_frame=first)
            write_motchallenge(tmp / "tracks.txt", pair.track_chunks(), groundtruth=False, first_frame=first)

        write_directory(Path(args.motchallenge), motchallenge, "--motchallenge")
    return 0


def _cmd_evaluate_nav(args) -> int:
    from evaluation.navigation_report import evaluate_nav_main

    check_json(args)
    print(evaluate_nav_main([Path(d) for d in args.run_dirs], Path(args.json) if args.json else None))
    return 0


def _cmd_navigate(args) -> int:
    from .navigate import navigate_main

    check_json(args)
    check_duration(args)
    scenario = _load(args, args.scenario)
    print(navigate_main(scenario, args.planner, args.first_seed, args.seeds, args.duration,
                        Path(args.json) if args.json else None, workers=args.workers, progress=not args.quiet,
                        ray=args.ray))
    return 0


def _cmd_report(args) -> int:
    from evaluation.io import EvaluationInputError
    from evaluation.report import write_report
    from evaluation.score import pct
    from scenarios import load_scenario
    from scenarios.geometry import wall_segments

    from .outdir import check_out_dir, write_directory

    run_dir = Path(args.run_dir)
    for name in ("scenario.yaml", "groundtruth.csv", "tracks.csv"):
        if not (run_dir / name).is_file():
            raise EvaluationInputError(f"{run_dir}: no {name}; expected a run directory that `crowdsim run` wrote")
    scenario = load_scenario(str(run_dir / "scenario.yaml"), allow_large=True)  # it ran as it is
    out = Path(args.out) if args.out else run_dir / "report"
    check_out_dir(out)
    title = f"{scenario.name}, seed {scenario.seed}"
    tracking = write_directory(out, lambda tmp: write_report(tmp, run_dir, wall_segments(scenario),
                                                             scenario.evaluation.threshold, title))
    print(f"MOTA {pct(tracking['mota'])}, IDF1 {pct(tracking['idf1'])}; report: {out / 'report.md'}")
    return 0


def _cmd_scenarios(args) -> int:
    from scenarios import bundled_scenarios

    scenarios = bundled_scenarios()
    width = max(map(len, scenarios), default=0)
    for name, description in scenarios.items():
        print(f"{name:{width}s}  {description}")
    return 0


def _cmd_validate_scenario(args) -> int:
    sc = _load(args, args.file)
    counts = {"waypoints": len(sc.waypoints), "queues": len(sc.queues), "routes": len(sc.routes),
              "sources": len(sc.sources), "clusters": len(sc.clusters), "standing": len(sc.standing)}
    walls = len(sc.map.segments)
    print(f"{args.file}: valid scenario {sc.name!r}: {walls} wall segments, "
          + ", ".join(f"{n} {k}" for k, n in counts.items())
          + f", {len(sc.sensors.lasers)} laser(s), {len(sc.sensors.depth_cameras)} depth camera(s), "
          f"{len(sc.sensors.wall_cameras)} wall camera(s); seed {sc.seed}, {sc.duration:g} s")
    return 0


def _cmd_scenario_keys(args) -> int:
    from scenarios.format import reference

    print(reference())
    return 0


def _cmd_validate(args) -> int:
    from .crowd.validation import run_validation
    from .outdir import write_directory

    out = run_dir(args, "validation")
    results = write_directory(out, lambda tmp: run_validation(tmp, quick=args.quick, progress=True))
    for check in results["checks"]:
        print(f"{'pass' if check['passed'] else 'FAIL'}  {check['name']}")
    print(f"largest overlap between two persons: {100 * results['safety']['max_overlap_m']:.1f} cm; "
          f"report: {out / 'report.md'}")
    return 0


def run_dir(args, name: str) -> Path:
    """A command's output folder: ``--out``, or runs/<name>-<time> (the name made one safe file name); checked
    before any work to be a new or empty folder this user can make."""
    from .outdir import check_out_dir

    safe = re.sub(r"[^A-Za-z0-9_.-]", "_", name).lstrip(".")[:100] or "run"
    out = args.out if args.out is not None else Path("runs") / f"{safe}-{time.strftime('%Y%m%d-%H%M%S')}"
    check_out_dir(out)  # as given: "" is refused, not read as "."
    out = Path(out)
    args.kept = f"nothing was kept: {out} was not written"
    return out


def check_json(args) -> None:
    """``--json``, when given, can take a new file: checked before any work."""
    from .outdir import check_out_file

    if args.json is not None:
        check_out_file(Path(args.json), "--json")


def check_duration(args) -> None:
    """``--duration``, when given, is a time above 0 s."""
    if args.duration is not None and not (math.isfinite(args.duration) and args.duration > 0):
        raise UsageError(f"--duration {args.duration}: expected a time above 0 s")


def add_out_argument(parser: argparse.ArgumentParser, name: str) -> None:
    """``--out`` of a command whose folder ``run_dir(args, name)`` makes."""
    parser.add_argument("--out", help=f"output directory (default runs/{name}-<time>); must be new or empty")


def _cmd_dataset_generate(args) -> int:
    try:
        from .datasets.generate import generate
    except ImportError as e:
        raise UsageError(f"crowdsim dataset: needs {e.name}, of the data extra: pip install -e \".[data]\"") from None
    scenarios = [_load(args, name) for name in args.scenarios]
    try:
        manifest = generate(scenarios, args.scenarios, args.out, args.episodes, seed=args.seed,  # "" refused as is
                            duration=args.duration, workers=args.workers, ray_address=args.ray, rate=args.rate_scale,
                            density=args.density_scale, route_jitter=args.route_jitter, compression=args.compression,
                            progress=not args.quiet, allow_large=args.allow_large)
    except BaseException as e:  # a stop or a failure: what was kept (complete episodes) is the generator's to say
        args.kept = getattr(e, "kept", getattr(args, "kept", "nothing was kept"))
        raise
    episodes = manifest["episodes"]
    size = sum(f["size"] for e in episodes for f in e["files"].values())
    frames = sum(e["frames"] for e in episodes)
    print(f"{args.out}: {len(episodes)} episodes, {frames:,} frames, {size / 1e6:,.1f} MB; splits "
          + ", ".join(f"{s} {len(ids)}" for s, ids in manifest["splits"].items()) + f", mini {len(manifest['mini'])}")
    return 0


def _cmd_dataset_export(args) -> int:
    import json

    from .datasets.export import export_dataset

    r = export_dataset(Path(args.folder), args.format, Path(args.out), args.split, args.laser)
    print(f"{r['out']}: {r['format']}, {r['episodes']} episodes, {r['files']} files, {r['bytes'] / 1e6:,.1f} MB")
    for key, value in r.items():
        if key not in ("out", "format", "episodes", "files", "bytes"):
            print(f"  {key}: {json.dumps(value)}")
    return 0


def _cmd_dataset_evaluate_detector(args) -> int:
    import json

    from .datasets.detection_eval import detection_table, evaluate_detector
    from .outdir import write_file

    check_json(args)
    result = evaluate_detector(Path(args.folder), args.detector, args.split, min_beams=args.min_beams)
    print(detection_table([result]))
    if args.json:
        write_file(Path(args.json), json.dumps(result.as_dict(), indent=1) + "\n")
    return 0


@dataclass(frozen=True)
class Command:
    """A registered subcommand (an experiment, a benchmark): its name, one line of help, and the module whose
    ``add_arguments(parser)`` declares its own flags and whose ``main(args) -> int`` runs it (``arguments`` and
    ``main`` name other functions of it). The module is imported only when the subcommand is chosen: importing every
    experiment would cost each ``crowdsim`` command seconds."""

    name: str
    help: str
    module: str
    arguments: str = "add_arguments"
    main: str = "main"


class _Parser(argparse.ArgumentParser):
    """argparse with the command's one-line errors: ``crowdsim: error: COMMAND: what was wrong`` and a pointer to
    the help, not a usage block (its subcommands' parsers are made of this class too). ``default_command``: the
    subcommand that arguments starting with a flag, or none, are given to (``crowdsim bench [--json F]`` is
    ``crowdsim bench loop [--json F]``)."""

    default_command: str | None = None

    def error(self, message: str):
        self.exit(2, f"crowdsim: error: {self.prog}: {message} (see `{self.prog} --help`)\n")

    def parse_known_args(self, args=None, namespace=None):
        if self.default_command is not None and args is not None and (
                not args or args[0].startswith("-") and args[0] not in ("-h", "--help")):
            args = [self.default_command, *args]
        return super().parse_known_args(args, namespace)


class _CommandParser(_Parser):
    """The parser of a registered ``Command``: its flags declared by its module on first use (a parse, its help)."""

    def __init__(self, *args, command: Command, **kwargs):
        super().__init__(*args, description=command.help, **kwargs)
        self.command = command
        self.declared = False

    def parse_known_args(self, args=None, namespace=None):
        if not self.declared:
            module = import_module(self.command.module)
            getattr(module, self.command.arguments)(self)
            self.set_defaults(func=getattr(module, self.command.main))
            self.declared = True
        namespace, extras = super().parse_known_args(args, namespace)
        if extras:  # named here, not by `crowdsim`: the flag is another experiment's, or none's
            self.error(f"unrecognized arguments: {' '.join(extras)}")
        return namespace, extras


def _add_commands(parser: _Parser, commands, title: str) -> None:
    """``parser``'s subcommands (``args.what``): one per registered ``Command``."""
    sub = parser.add_subparsers(dest="what", metavar=title, required=True, parser_class=_CommandParser)
    for command in commands:
        sub.add_parser(command.name, help=command.help, command=command)


def build_parser() -> argparse.ArgumentParser:
    from . import workers
    from .bench import BENCHMARKS
    from .experiments import EXPERIMENTS

    parser = _Parser(prog="crowdsim", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("run", help="simulate a scenario, track, score, and write a run directory")
    p.add_argument("scenario", help="a bundled scenario name (see `crowdsim scenarios`) or a YAML file")
    p.add_argument("--seed", type=int, help="override the scenario's seed")
    p.add_argument("--duration", type=float, help="override the scenario's duration (simulated seconds)")
    p.add_argument("--out", help="output directory (default runs/<scenario>-<time>); must be new or empty")
    p.add_argument("--rrd", action="store_true", help="also write a rerun recording, recording.rrd")
    p.add_argument("--allow-large", action="store_true",
                   help="run a scenario past the cost limits (steps, beams, pixels, grid cells, people) on purpose")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_run)
    p = sub.add_parser("evaluate", help="score any tracker's output (the CSV layout `crowdsim run` writes) against "
                                        "ground truth")
    p.add_argument("--gt", help="ground truth CSV (header with frame,id,x,y and visible unless --no-occlusion; "
                                "optional t, in_range, range, ...)")
    p.add_argument("--tracks", help="tracks CSV (header with frame,id,x,y; other columns allowed)")
    p.add_argument("--runs", nargs="+", metavar="DIR",
                   help="instead of --gt and --tracks: run directories (the same scenario at several seeds, say), "
                        "scored each and summed up as mean and standard deviation, as seed 001's tables")
    p.add_argument("--threshold", type=float, default=1.0,
                   help="match distance in metres (default 1, as seed 000; seeds 001 and 003 use 0.3)")
    p.add_argument("--max-range", type=float, help="ignore ground truth farther than this from the robot (m; "
                                                  "seed 000's real data: 12) -- needs a range column")
    p.add_argument("--no-occlusion", action="store_true",
                   help="count occluded persons as misses (by default the ground truth's visible column, which it "
                        "must then have, ignores them)")
    p.add_argument("--visible-column", default="visible",
                   help="the ground truth's visibility column: visible (any laser beam hit them, default) or "
                        "visible_seed000 (seed 000's rule: a laser point within 0.3 m of the position moved 0.2 m "
                        "towards the laser)")
    p.add_argument("--relations", help="relations CSV (frame,track_a,track_b,strength), with --groups: score the "
                                       "groups too (the ground truth needs a group column)")
    p.add_argument("--groups", help="groups CSV (frame,group,id: one row per member track)")
    p.add_argument("--json", help="write {\"tracking\": ..., \"groups\": ...} with the keys of metrics.json to this "
                                  "new file (with --runs: {\"runs\": [...], \"mean\": ..., \"sd\": ..., "
                                  "\"groups\": {dir: ...}})")
    p.add_argument("--motchallenge", help="also export gt.txt and tracks.txt, MOTChallenge-style, into this new or "
                                          "empty directory")
    p.set_defaults(func=_cmd_evaluate)
    p = sub.add_parser("evaluate-nav", help="navigation metrics (outcome, path, smoothness, social, passers-by, "
                                            "following) of run directories from their logged trajectories")
    p.add_argument("run_dirs", nargs="+", metavar="RUN_DIR",
                   help="directories with robot.csv, persons.csv, navigation.json (and following.csv for a "
                        "following task): layouts in docs/navigation-metrics.md")
    p.add_argument("--json", help="also write {\"runs\": [...], \"mean\": ..., \"sd\": ...} to this new file")
    p.set_defaults(func=_cmd_evaluate_nav)
    p = sub.add_parser("navigate", help="a planner over a fixed suite of seeds of a navigation scenario (driver "
                                        "goals or follow), scored in memory: the navigation metrics' mean and sd")
    p.add_argument("scenario", help="a bundled scenario name or a YAML file whose robot.driver is goals or follow")
    p.add_argument("--planner",
                   help="zone, nd, straight, social_force or module.path:ClassName (the scenario's own parameters "
                        "when it names that type, else the type's defaults); default: the scenario's robot.planner")
    p.add_argument("--seeds", type=int, required=True, help="episodes: seeds S..S+N-1")
    p.add_argument("--first-seed", type=int, default=1, help="S, the suite's first seed (default 1)")
    p.add_argument("--allow-large", action="store_true",
                   help="run a scenario past the cost limits (steps, beams, pixels, grid cells, people) on purpose")
    p.add_argument("--duration", type=float, help="each episode's time limit in s (default: the scenario's duration)")
    workers.add_arguments(p, workers=1)
    p.add_argument("--json", help="also write every episode's figures, their mean and sd and the counts to this "
                                  "new file")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_navigate)
    p = sub.add_parser("report", help="report.md with the metric tables and figures of a run directory")
    p.add_argument("run_dir", help="a directory `crowdsim run` wrote")
    p.add_argument("--out", help="where to write it (default RUN_DIR/report); must be new or empty")
    p.set_defaults(func=_cmd_report)
    p = sub.add_parser("scenarios", help="list the bundled scenarios")
    p.set_defaults(func=_cmd_scenarios)
    p = sub.add_parser("validate-scenario", help="check a scenario file and say what it holds")
    p.add_argument("file", help="a YAML scenario (or a bundled name)")
    p.add_argument("--allow-large", action="store_true",
                   help="run a scenario past the cost limits (steps, beams, pixels, grid cells, people) on purpose")
    p.set_defaults(func=_cmd_validate_scenario)
    p = sub.add_parser("validate", help="the crowd model against RiMEA tests 1, 4, 6, 7, Weidmann and bottlenecks")
    p.add_argument("--out", help="report directory (default runs/validation-<time>); must be new or empty")
    p.add_argument("--quick", action="store_true", help="the same checks at a smaller size")
    p.set_defaults(func=_cmd_validate)
    p = sub.add_parser("scenario-keys", help="every key of the scenario format: kind, default, range, meaning")
    p.set_defaults(func=_cmd_scenario_keys)
    p = sub.add_parser("bench", help="measure the crowd, the lasers, the trackers, the group stage and the loop; "
                                     "`bench sim`: the crowd against JuPedSim; `bench sensors`: every sensor; "
                                     "`bench eval`: the evaluation; `bench env`: the gym environments; "
                                     "`bench dataset`: dataset generation")
    p.default_command = "loop"
    _add_commands(p, BENCHMARKS, "BENCHMARK")
    p = sub.add_parser("experiment", help="experiments that take long: `experiment ppo` trains PPO on Navigate-v0, "
                                          "`experiment train-detector` the laser_learned segment classifiers, "
                                          "`experiment train-relations` the group stage's relation classifiers")
    _add_commands(p, EXPERIMENTS, "EXPERIMENT")
    p = sub.add_parser("dataset", help="labelled datasets: generate, export, evaluate-detector "
                                       "(docs/dataset-format.md)")
    dataset = p.add_subparsers(dest="dataset_command", required=True)
    p = dataset.add_parser("generate", help="N episodes of labelled sensor data, in parallel and resumably")
    p.add_argument("scenarios", nargs="+", metavar="SCENARIO",
                   help="bundled names or files; episode k runs the (k mod S)-th of the S given")
    p.add_argument("--episodes", type=int, required=True, help="episodes in all")
    p.add_argument("--out", required=True, help="the dataset folder: new, empty, or a dataset of this very "
                                                "command, which is verified and completed; with --ray on a "
                                                "cluster, one every node writes to")
    p.add_argument("--seed", type=int, default=0, help="root seed S: episode k is seeded from "
                                                       "SeedSequence(S).spawn(...)[k] (default 0)")
    p.add_argument("--duration", type=float, help="s recorded per episode (default: the scenario's)")
    workers.add_arguments(p, workers=1)
    p.add_argument("--allow-large", action="store_true",
                   help="run a scenario past the cost limits (steps, beams, pixels, grid cells, people) on purpose")
    p.add_argument("--rate-scale", type=float, nargs=2, metavar=("LO", "HI"),
                   help="per episode, every source's rate times a factor uniform in [LO, HI]")
    p.add_argument("--density-scale", type=float, nargs=2, metavar=("LO", "HI"),
                   help="per episode, every agent cluster's and standing group's count times a factor uniform in "
                        "[LO, HI]")
    p.add_argument("--route-jitter", type=float, default=0.0, metavar="M",
                   help="per episode, the robot's start and, if it has a route, each route waypoint moved within M "
                        "m, never through a wall (default 0)")
    p.add_argument("--compression", choices=("gzip", "lzf", "none"), default="gzip",
                   help="sensors.h5's chunk compression (Parquet: zstd unless none; default gzip)")
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    p.set_defaults(func=_cmd_dataset_generate)
    p = dataset.add_parser("export", help="a dataset in another format: DROW, MOTChallenge, ROS 2 or ROS 1 bags")
    p.add_argument("folder", metavar="DIR", help="a dataset folder (crowdsim dataset generate)")
    p.add_argument("--format", required=True, choices=("drow", "motchallenge", "rosbag2", "rosbag1"),
                   help="the format to write")
    p.add_argument("--out", required=True, help="where to write it: a new or empty folder")
    p.add_argument("--split", help="train, val, test or mini (default: every episode)")
    p.add_argument("--laser", help="drow: the laser to export (default: the first on DROW's beam grid, as the "
                                   "sick_s300 preset makes it)")
    p.set_defaults(func=_cmd_dataset_export)
    p = dataset.add_parser("evaluate-detector", help="a detector's detections in a dataset scored as DR-SPAAM: AP, "
                                                     "peak F1 and EER at 0.3 and 0.5 m")
    p.add_argument("folder", metavar="DIR", help="a dataset folder (crowdsim dataset generate)")
    p.add_argument("--detector", default="fusion", help="a laser's name, or fusion (default): the fused detections")
    p.add_argument("--split", default="test", help="train, val, test (default) or mini")
    p.add_argument("--min-beams", type=int, default=6, metavar="K",
                   help="score persons hit by at least K beams of the detector's laser (fusion: of any laser); "
                        "default 6, DR-SPAAM's more than 5 points")
    p.add_argument("--json", help="also write the counts and scores to this new file")
    p.set_defaults(func=_cmd_dataset_evaluate_detector)
    return parser


# a write that failed for want of room: the disk or the user's quota full, or a file-size limit (ulimit -f)
NO_ROOM = (errno.ENOSPC, errno.EDQUOT, errno.EFBIG)


def main(argv: list[str] | None = None) -> int:
    from .stops import Stopped, stops_as_exceptions

    args = build_parser().parse_args(argv)
    with warnings.catch_warnings(), stops_as_exceptions():  # both restored on return
        warnings.showwarning = _show_warning
        try:
            return args.func(args)
        except Error as e:
            kept = getattr(e, "kept", None)  # what a command that fails halfway keeps (a dataset's episodes)
            print(f"crowdsim: error: {e}" + (f"; {kept}" if kept else ""), file=sys.stderr)
            return 2
        except OSError as e:
            if e.errno not in NO_ROOM:
                raise
            from .outdir import final_path

            where = f"{final_path(str(e.filename))}: " if e.filename else ""
            print(f"crowdsim: error: {where}{e.strerror}; expected room to write the output "
                  f"({getattr(args, 'kept', 'nothing was kept')})", file=sys.stderr)
            return 2
        except Stopped as e:
            print(f"crowdsim: stopped by {e}; {getattr(args, 'kept', 'nothing was written')}", file=sys.stderr,
                  flush=True)
            return 128 + e.signum  # the status a shell gives a process that the signal ended


if __name__ == "__main__":
    sys.exit(main())

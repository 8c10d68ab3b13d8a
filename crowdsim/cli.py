"""The ``crowdsim`` command: run, evaluate, evaluate-nav, navigate, report, scenarios, validate-scenario, validate,
scenario-keys, bench."""

from __future__ import annotations

import argparse
import errno
import math
import re
import sys
import time
import warnings
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
    out = _run_dir(args, scenario["name"])
    metrics = run(scenario, out, rrd=args.rrd, progress=not args.quiet)
    print(summary_table(metrics))
    if "navigation" in metrics:
        print(f"\nnavigation ({'goal' if scenario['robot']['driver'] == 'goals' else 'following'}, "
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

    from evaluation.group_score import groups_table, score_groups
    from evaluation.io import EvaluationInputError, write_motchallenge
    from evaluation.score import (SEED000_COLUMNS, SEED001_COLUMNS, mean_sd, score_tracking, seeds_table,
                                  tracking_table)
    from evaluation.stream import CsvPair

    from .outdir import check_out_dir, write_directory, write_file

    _check_json(args)
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

    def group_scores(gt_path, tracks_path, relations_path, groups_path) -> dict:
        return score_groups(gt_path, tracks_path, relations_path, groups_path, args.threshold,
                            not args.no_occlusion, args.visible_column, args.max_range)

    def files(gt_path, tracks_path) -> CsvPair:
        return CsvPair(gt_path, tracks_path, occlusion=not args.no_occlusion, visible_column=args.visible_column,
                       max_range=args.max_range)

    if args.runs:
        if args.motchallenge is not None:
            raise EvaluationInputError("--motchallenge exports one pair of files: give --gt and --tracks")
        runs = [score_tracking(files(Path(d) / "groundtruth.csv", Path(d) / "tracks.csv"), args.threshold)
                for d in args.runs]
        # every file scored before anything is printed: a bad one is the one line printed
        with_groups = [Path(d) for d in args.runs if all((Path(d) / f).is_file() for f in GROUP_FILES)]
        groups = [group_scores(*(d / f for f in ("groundtruth.csv", "tracks.csv", *GROUP_FILES)))
                  for d in with_groups]
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
    pair = files(args.gt, args.tracks)
    tracking = score_tracking(pair, args.threshold)
    report = {"tracking": tracking}
    if args.relations:  # scored before anything is printed: a bad group file is the one line printed
        report["groups"] = group_scores(args.gt, args.tracks, args.relations, args.groups)
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

    _check_json(args)
    print(evaluate_nav_main([Path(d) for d in args.run_dirs], Path(args.json) if args.json else None))
    return 0


def _cmd_navigate(args) -> int:
    from .navigate import navigate_main

    _check_json(args)
    if args.duration is not None and not (math.isfinite(args.duration) and args.duration > 0):
        raise UsageError(f"--duration {args.duration}: expected a time above 0 s")
    scenario = _load(args, args.scenario)
    print(navigate_main(scenario, args.planner, args.first_seed, args.seeds, args.duration,
                        Path(args.json) if args.json else None, workers=args.workers, progress=not args.quiet))
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
    title = f"{scenario['name']}, seed {scenario['seed']}"
    tracking = write_directory(out, lambda tmp: write_report(tmp, run_dir, wall_segments(scenario),
                                                             scenario["evaluation"]["threshold"], title))
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
    counts = {k: len(sc[k]) for k in ("waypoints", "queues", "routes", "sources", "clusters", "standing")}
    walls = sum(len(w) - 1 for w in sc["map"]["walls"]) + sum(len(o) for o in sc["map"]["obstacles"])
    print(f"{args.file}: valid scenario {sc['name']!r}: {walls} wall segments, "
          + ", ".join(f"{n} {k}" for k, n in counts.items())
          + f", {len(sc['sensors']['lasers'])} laser(s), {len(sc['sensors']['depth_cameras'])} depth camera(s), "
          f"{len(sc['sensors']['wall_cameras'])} wall camera(s); seed {sc['seed']}, {sc['duration']:g} s")
    return 0


def _cmd_scenario_keys(args) -> int:
    from scenarios.format import reference

    print(reference())
    return 0


def _cmd_validate(args) -> int:
    from .crowd.validation import run_validation
    from .outdir import write_directory

    out = _run_dir(args, "validation")
    results = write_directory(out, lambda tmp: run_validation(tmp, quick=args.quick, progress=True))
    for check in results["checks"]:
        print(f"{'pass' if check['passed'] else 'FAIL'}  {check['name']}")
    print(f"largest overlap between two persons: {100 * results['safety']['max_overlap_m']:.1f} cm; "
          f"report: {out / 'report.md'}")
    return 0


def _cmd_bench(args) -> int:
    _check_json(args)
    if args.what == "sim":
        from .bench.sim import run_sim_benchmark

        run_sim_benchmark(quick=args.quick, json_path=args.json)
    elif args.what == "eval":
        from .bench.eval import run_eval_benchmark

        run_eval_benchmark(json_path=args.json, quick=args.quick)
    elif args.what == "env":
        from .bench.env import run_env_benchmark

        if args.socnavgym and not args.socnavgym_config:
            raise UsageError("--socnavgym: expected --socnavgym-config too (one of SocNavGym's environment configs)")
        run_env_benchmark(json_path=args.json, quick=args.quick, crowdnav=args.crowdnav,
                          crowdnav_dir=args.crowdnav_dir, socnavgym=args.socnavgym,
                          socnavgym_config=args.socnavgym_config)
    elif args.what == "dataset":
        from .bench.dataset import run_dataset_benchmark

        run_dataset_benchmark(json_path=args.json, quick=args.quick)
    elif args.what == "sensors":
        from .bench.sensors import run_sensor_benchmarks

        run_sensor_benchmarks(json_path=args.json, quick=args.quick)
    else:
        from .bench.parts import run_benchmarks

        run_benchmarks(json_path=args.json, quick=args.quick)
    return 0


# --seeds left out: how many each experiment takes
DEFAULT_SEEDS = {"train-detector": 20, "table2": 20, "train-relations": 20, "groups": 5, "train-hog": 10,
                 "seed003": 1}


def _cmd_experiment(args) -> int:
    from .outdir import write_directory

    if args.seeds is None:
        args.seeds = DEFAULT_SEEDS.get(args.what)
    if args.what == "train-detector":
        return _cmd_train_detector(args)
    if args.what == "train-relations":
        return _cmd_train_relations(args)
    if args.what == "train-hog":
        return _cmd_train_hog(args)
    if args.what == "groups":
        from .experiments.groups import held_out_seeds, run, write

        if args.seeds < 1 or args.workers < 1:
            raise UsageError(f"--seeds and --workers: expected at least 1, got {args.seeds} and {args.workers}")
        seeds = held_out_seeds(args.seeds)
        out = _run_dir(args, "groups")
        results = run(seeds, args.duration or 60.0, workers=args.workers)
        print(write_directory(out, lambda tmp: write(tmp, results, seeds)))
        print(f"\n{out / 'groups.md'}, groups.json, groups.png")
        return 0
    if args.what == "hog-vs-opencv":
        try:
            import cv2  # noqa: F401
        except ImportError:
            raise UsageError('experiment hog-vs-opencv: needs OpenCV: pip install -e ".[compare]"') from None
        from .experiments.train_hog import compare_opencv

        r = compare_opencv(workers=args.workers)
        print(f"HOG person detectors on held-out seeds {r['test_seeds']} ({r['images']} images, "
              f"{r['ours_peak']['persons']} persons), a detection right at IoU 0.5:\n")
        print("| detector | F1 | precision | recall |\n|---|---|---|---|")
        for label, key in (("ours, at its threshold (validation seeds)", "ours_at_threshold"),
                           ("ours, at its best threshold here", "ours_peak"),
                           ("OpenCV's INRIA-trained, at its best threshold here", "opencv_peak")):
            print(f"| {label} | {r[key]['f1']:.3f} | {r[key]['precision']:.3f} | {r[key]['recall']:.3f} |")
        return 0
    if args.what == "seed001":
        from .experiments.seed001 import experiment, write

        if args.runs < 1 or args.workers < 1:
            raise UsageError(f"--runs and --workers: expected at least 1, got {args.runs} and {args.workers}")
        out = _run_dir(args, "seed001")
        if args.tune:
            from .experiments.seed001 import tune, write_tuning

            print(write_directory(out, lambda tmp: write_tuning(tmp, tune(workers=args.workers))))
            return 0
        results = experiment(args.runs, workers=args.workers)
        print(write_directory(out, lambda tmp: write(tmp, results)))
        print(f"\n{out / 'seed001.md'}, seed001.json, seed001.png")
        return 0
    if args.what == "seed003":
        from .experiments.seed003 import experiment, write

        if args.seeds < 1 or args.workers < 1:
            raise UsageError(f"--seeds and --workers: expected at least 1, got {args.seeds} and {args.workers}")
        out = _run_dir(args, "seed003")
        results = experiment(args.seeds, workers=args.workers, preset=args.preset)
        print(write_directory(out, lambda tmp: write(tmp, results)))
        print(f"\n{out / 'seed003.md'}, seed003.json, seed003.png")
        return 0
    if args.what == "table2":
        from .experiments.table2 import table2, write

        if args.seeds < 1:
            raise UsageError(f"--seeds: expected at least 1, got {args.seeds}")
        seeds = list(range(1, args.seeds + 1))
        out = _run_dir(args, "table2")
        figures = table2(seeds, args.duration, workers=args.workers)
        print(write_directory(out, lambda tmp: write(tmp, figures, seeds)))
        print(f"\n{out / 'table2.md'}, table2.json, table2.png")
        return 0
    if args.what == "tune":
        try:
            from .experiments.tune import tune
        except ImportError as e:
            raise UsageError(f"experiment tune: needs {e.name}: pip install -e \".[tune]\"") from None
        out = _run_dir(args, "tune")
        r = write_directory(out, lambda tmp: tune(tmp, args.trials, args.storage, duration=args.duration or 60.0,
                                                  seed=args.seed))
        print(f"{r['trials']} trials; best MOTA {r['best_train_mota']:.1f}% on the training seeds; held out: "
              f"{r['held_out_mota_best']:.1f}% against the airport's own {r['held_out_mota_airport']:.1f}%; "
              f"{out / 'best.yaml'}")
        return 0
    if args.minutes <= 0:
        raise UsageError(f"--minutes: expected a time above 0, got {args.minutes}")
    out = _run_dir(args, "ppo")
    from .experiments.ppo import run_ppo

    r = write_directory(out, lambda tmp: run_ppo(tmp, args.minutes, envs=args.envs, people=args.people,
                                                 seed=args.seed, eval_episodes=args.eval_episodes))
    print(f"PPO: {r['steps']:,} steps in {r['train_wall_s'] / 60:.1f} min ({r['steps_per_s']:.0f}/s), "
          f"{r['training_episodes']} training episodes")
    for name in ("ppo", "random"):
        e = r[name]
        print(f"{name:7s} on {e['episodes']} evaluation seeds: success {e['success_rate']:.0%}, collision "
              f"{e['collision_rate']:.0%}, timeout {e['timeout_rate']:.0%}, mean return {e['mean_return']:.2f}")
    print(f"learning curve: {out / 'learning_curve.png'}")
    return 0


def _run_dir(args, name: str) -> Path:
    """A command's output folder: ``--out``, or runs/<name>-<time> (the name made one safe file name); checked
    before any work to be a new or empty folder this user can make."""
    from .outdir import check_out_dir

    safe = re.sub(r"[^A-Za-z0-9_.-]", "_", name).lstrip(".")[:100] or "run"
    out = args.out if args.out is not None else Path("runs") / f"{safe}-{time.strftime('%Y%m%d-%H%M%S')}"
    check_out_dir(out)  # as given: "" is refused, not read as "."
    out = Path(out)
    args.kept = f"nothing was kept: {out} was not written"
    return out


def _check_json(args) -> None:
    """``--json``, when given, can take a new file: checked before any work."""
    from .outdir import check_out_file

    if args.json is not None:
        check_out_file(Path(args.json), "--json")


def _training_out(args) -> Path | None:
    """A training command's ``--out`` (None: the shipped models' folder), checked to be new or empty, once
    scikit-learn is known to be there."""
    from .outdir import check_out_dir

    out = None
    if args.out is not None:  # "" is refused, not taken for the shipped models' folder
        check_out_dir(args.out)
        out = Path(args.out)
    try:
        import sklearn  # noqa: F401
    except ImportError:
        raise UsageError(f'experiment {args.what} needs scikit-learn, of the train extra: '
                         'pip install -e ".[train]"') from None
    return out


def _saved(models, save_models, out: Path | None, models_dir: Path) -> list[Path]:
    """``save_models`` into the shipped models' folder, or into ``out`` whole (written beside, then moved)."""
    from .outdir import write_directory

    if out is None:
        return save_models(models, models_dir)
    return [out / p.name for p in write_directory(out, lambda tmp: save_models(models, tmp))]


def _cmd_train_detector(args) -> int:
    if not 1 <= args.seeds <= 1000:
        raise UsageError(f"--seeds: expected 1 to 1000 training seeds, got {args.seeds}")
    if args.workers < 1:
        raise UsageError(f"--workers: expected at least 1 process, got {args.workers}")
    out = _training_out(args)
    from pipeline.detectors.learned_segments import MODELS_DIR

    from .experiments.train_detector import save_models, train

    t0 = time.perf_counter()
    models, report = train(args.seeds, quick=args.quick, workers=args.workers)
    paths = _saved(models, save_models, out, MODELS_DIR)
    print(report)
    print(f"{time.perf_counter() - t0:.0f} s; models: " + _sizes(paths))
    return 0


def _training_seeds_out(args, most: int, first: int) -> Path | None:
    """``_training_out`` after checking --seeds (1 to ``most`` training seeds from ``first``) and --workers."""
    if not 1 <= args.seeds <= most or args.workers < 1:
        raise UsageError(f"--seeds: expected 1 to {most} training seeds (from {first}), and --workers at least 1; "
                         f"got {args.seeds} and {args.workers}")
    return _training_out(args)


def _sizes(paths: list[Path]) -> str:
    return ", ".join(f"{p} ({p.stat().st_size / 1024:.0f} KiB)" for p in paths)


def _cmd_train_relations(args) -> int:
    out = _training_seeds_out(args, 20, 1100)
    from pipeline.groups.relations import MODELS_DIR

    from .experiments.relations import save_models, train

    t0 = time.perf_counter()
    models = train(args.seeds, args.duration or 60.0, workers=args.workers)
    paths = _saved(models, save_models, out, MODELS_DIR)
    info = next(iter(models.values()))[1]
    print(f"{info['pairs']} pairs of tracks ({info['related']} related) from seeds {info['train_seeds'][0]}-"
          f"{info['train_seeds'][1]}; {time.perf_counter() - t0:.0f} s; models: " + _sizes(paths))
    return 0


def _cmd_train_hog(args) -> int:
    from .experiments.train_hog import DURATION, MODELS_DIR, save

    if args.camera == "robot":
        from pipeline.detectors.hog import ROBOT_MODEL_FILE

        from .experiments.train_hog_robot import train
        out = _training_seeds_out(args, 100, 5100)
    else:
        from .experiments.train_hog import train
        out = _training_seeds_out(args, 100, 4100)
    t0 = time.perf_counter()
    model, info = train(args.seeds, args.workers, args.duration or DURATION)
    name = ROBOT_MODEL_FILE if args.camera == "robot" else None
    paths = _saved((model, info), lambda m, where: [save(*m, where, *([name] if name else []))], out, MODELS_DIR)
    v = info["validation"]
    print(f"{info['positives']} person windows, {info['negatives']} random and {info['hard_negatives']} hard "
          f"negatives from seeds {info['train_seeds'][0]}-{info['train_seeds'][1]}; ", end="")
    if args.camera == "robot":
        print(f"threshold {model.threshold:.3f} ({info['threshold_recall']:.0%} of the {v['candidates_on_persons']} "
              f"validation candidates on persons pass, {v['false_above_threshold']:.1%} of the "
              f"{v['candidates_on_no_one']} on no one), track start {info['start_confidence']:.3f} "
              f"({info['start_recall']:.0%} pass, {v['false_above_start']:.1%}); ", end="")
    else:
        print(f"validation (IoU 0.5): F1 {v['f1']:.3f}, precision {v['precision']:.3f}, recall {v['recall']:.3f} at "
              f"score {model.threshold:.3f}; ", end="")
    print(f"{time.perf_counter() - t0:.0f} s; model: " + _sizes(paths))
    return 0


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

    _check_json(args)
    result = evaluate_detector(Path(args.folder), args.detector, args.split, min_beams=args.min_beams)
    print(detection_table([result]))
    if args.json:
        write_file(Path(args.json), json.dumps(result.as_dict(), indent=1) + "\n")
    return 0


class _Parser(argparse.ArgumentParser):
    """argparse with the command's one-line errors: ``crowdsim: error: COMMAND: what was wrong`` and a pointer to
    the help, not a usage block (its subcommands' parsers are made of this class too)."""

    def error(self, message: str):
        self.exit(2, f"crowdsim: error: {self.prog}: {message} (see `{self.prog} --help`)\n")


def build_parser() -> argparse.ArgumentParser:
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
    p.add_argument("--workers", type=int, default=1, help="processes the seeds are shared among (default 1; 2 on "
                                                          "two cores)")
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
                                     "`bench eval`: the evaluation; `bench env`: the gym environments; `bench dataset`: "
                                     "dataset generation")
    p.add_argument("what", nargs="?", choices=("loop", "sim", "sensors", "eval", "env", "dataset"),
                   default="loop",
                   help="loop (default): every part and the airport loop; sim: the crowd simulator at 100, 1000 "
                        "and 5000 agents side by side with JuPedSim's social force model; sensors: each sensor's "
                        "cost with 100 and 500 people, batched rays, and the robot's sensor mix against real time; "
                        "eval: the evaluation's frames/s on 5000 frames of 80 persons; env: environment steps/s, "
                        "one env and the vector envs; dataset: a dataset episode's frames/s and bytes per frame")
    p.add_argument("--json", help="also write the figures to this JSON file")
    p.add_argument("--quick", action="store_true", help="shorter measurements (for a smoke test)")
    p.add_argument("--crowdnav", metavar="PYTHON", help="bench env: also time CrowdNav with this interpreter")
    p.add_argument("--crowdnav-dir", metavar="DIR", help="bench env: CrowdNav's checkout, if not installed")
    p.add_argument("--socnavgym", metavar="PYTHON", help="bench env: also time SocNavGym with this interpreter")
    p.add_argument("--socnavgym-config", metavar="FILE", help="bench env: the SocNavGym environment config to use")
    p.set_defaults(func=_cmd_bench)
    p = sub.add_parser("experiment", help="experiments that take long: `experiment ppo` trains PPO on Navigate-v0, "
                                          "`experiment train-detector` the laser_learned segment classifiers, "
                                          "`experiment train-relations` the group stage's relation classifiers")
    p.add_argument("what", choices=("ppo", "train-detector", "table2", "tune", "train-relations", "groups",
                                     "train-hog", "seed001", "hog-vs-opencv", "seed003"),
                   help="ppo: stable-baselines3 PPO on crowdsim/Navigate-v0 with the tracks observation, against "
                        "the random policy (needs [rl]); train-detector: AdaBoost and random-forest segment "
                        "classifiers on labelled airport scans, scored against laser_segments on held-out seeds "
                        "(needs [train]); table2: seed 000's Table II on the airport over --seeds seeds (from 1), "
                        "its claims checked; tune: Optuna over the pipeline's parameters for MOTA (needs [tune]); "
                        "train-relations: the svm and forest relation classifiers on tracker output of airport seeds "
                        "1100-1119 (needs [train]); groups: the group stage on held-out airport seeds (from 1200): "
                        "each classifier against SPENCER's, each linkage, thresholds, tracker against true tracks; "
                        "train-hog: the wall cameras' HOG person detector on rendered images of seed 001's room "
                        "(needs [train]); seed001: seed 001's Tables 2-6, its RJMCMC filter over the laser and the "
                        "wall cameras in four modes on sequences I-III, its claims checked; hog-vs-opencv: our HOG "
                        "model against OpenCV's INRIA-trained one on held-out images (needs [compare]); seed003: "
                        "seed 003's Tables 2-5, its RGB-D detector and tracker on the KTP-like room's five "
                        "situations under four robot motions, in five variants, its claims checked")
    p.add_argument("--minutes", type=float, default=30.0, help="wall-clock training budget (default 30)")
    p.add_argument("--envs", type=int, default=8, help="environments stepped together (default 8)")
    p.add_argument("--people", type=int, default=10, help="people per environment (default 10)")
    p.add_argument("--seed", type=int, default=0, help="training seed (evaluation seeds are disjoint)")
    p.add_argument("--eval-episodes", type=int, default=100, help="evaluation episodes per policy (default 100)")
    p.add_argument("--out", help="output directory (default runs/<what>-<time>; train-detector, train-relations and "
                                 "train-hog: the shipped models, pipeline/detectors/models/ or "
                                 "pipeline/groups/models/, replaced); must be new or empty")
    p.add_argument("--camera", choices=("wall", "robot"), default="wall",
                   help="train-hog: the wall cameras' model (seed 001's room) or the robot depth camera's (seed 003's "
                        "KTP room, training seeds from 5100)")
    p.add_argument("--seeds", type=int, help="train-detector: training seeds, from 1000 (default 20); table2: seeds "
                                             "from 1 (default 20); train-relations: training seeds, from 1100 "
                                             "(default 20); groups: held-out seeds, from 1200 (default 5); "
                                             "train-hog: training seeds, from 4100 (default 10); seed003: "
                                             "evaluation seeds from 1, each 20 runs (default 1)")
    p.add_argument("--preset", choices=("kinect_160", "kinect_640"), default="kinect_160",
                   help="seed003: the robot camera's resolution (default kinect_160, QQVGA, as seed 003's timing)")
    p.add_argument("--duration", type=float, help="table2, tune, train-relations and groups: s of each airport run "
                                                  "(default: the scenario's; the others: 60)")
    p.add_argument("--runs", type=int, default=8, help="seed001: filter runs per sequence and mode (default 8, as "
                                                       "seed 001's)")
    p.add_argument("--tune", action="store_true", help="seed001: choose the filter's pooled-likelihood parameters on "
                                                       "training sequences (rooms 3 and 2 at seeds 4000, 4001) in "
                                                       "place of the tables: tune.md, tune.json")
    p.add_argument("--trials", type=int, default=50, help="tune: trials (default 50)")
    p.add_argument("--storage", help="tune: an Optuna storage to keep and resume the study, e.g. sqlite:///study.db")
    p.add_argument("--quick", action="store_true", help="train-detector: 4 short training seeds, 1 validation and "
                                                        "1 test seed (a smoke test, not models to ship)")
    p.add_argument("--workers", type=int, default=2, help="train-detector, table2, train-relations, groups, "
                                                          "seed001 and seed003: processes running the simulations "
                                                          "(default 2)")
    p.set_defaults(func=_cmd_experiment)
    p = sub.add_parser("dataset", help="labelled datasets: generate, export, evaluate-detector "
                                       "(docs/dataset-format.md)")
    dataset = p.add_subparsers(dest="dataset_command", required=True)
    p = dataset.add_parser("generate", help="N episodes of labelled sensor data, in parallel and resumably")
    p.add_argument("scenarios", nargs="+", metavar="SCENARIO",
                   help="bundled names or files; episode k runs the (k mod S)-th of the S given")
    p.add_argument("--episodes", type=int, required=True, help="episodes in all")
    p.add_argument("--out", required=True, help="the dataset folder: new, empty, or a dataset of this very "
                                                "command, which is verified and completed")
    p.add_argument("--seed", type=int, default=0, help="root seed S: episode k is seeded from "
                                                       "SeedSequence(S).spawn(...)[k] (default 0)")
    p.add_argument("--duration", type=float, help="s recorded per episode (default: the scenario's)")
    p.add_argument("--workers", type=int, default=1, help="local processes (default 1)")
    p.add_argument("--allow-large", action="store_true",
                   help="run a scenario past the cost limits (steps, beams, pixels, grid cells, people) on purpose")
    p.add_argument("--ray", nargs="?", const="local", metavar="ADDRESS",
                   help="run the episodes as Ray tasks: on the cluster at ADDRESS, or a local one (needs [ray]); "
                        "the folder must be one every node writes to")
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

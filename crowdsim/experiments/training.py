"""What the training experiments' commands share: ``--out`` (the shipped models' folder, or a new or empty one), the
models saved there, and their sizes shown. And ``crowdsim experiment train-relations``'s command, whose code is
``relations.py``'s."""

from __future__ import annotations

import time
from pathlib import Path

from .. import workers
from ..workers import Engine


def add_models_out_argument(parser, models: str) -> None:
    """``--out`` of a training command whose models ship in the folder ``models``."""
    parser.add_argument("--out", help=f"output directory (default: the shipped models, {models}, replaced); must "
                                      "be new or empty")


def training_out(args) -> Path | None:
    """A training command's ``--out`` (None: the shipped models' folder), checked to be new or empty, once
    scikit-learn is known to be there."""
    from ..cli import UsageError
    from ..outdir import check_out_dir

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


def training_seeds_out(args, most: int, first: int) -> Path | None:
    """``training_out`` after checking --seeds (1 to ``most`` training seeds from ``first``) and --workers."""
    from ..cli import UsageError

    if not 1 <= args.seeds <= most or args.workers < 1:
        raise UsageError(f"--seeds: expected 1 to {most} training seeds (from {first}), and --workers at least 1; "
                         f"got {args.seeds} and {args.workers}")
    return training_out(args)


def saved(models, save_models, out: Path | None, models_dir: Path) -> list[Path]:
    """``save_models`` into the shipped models' folder, or into ``out`` whole (written beside, then moved)."""
    from ..outdir import write_directory

    if out is None:
        return save_models(models, models_dir)
    return [out / p.name for p in write_directory(out, lambda tmp: save_models(models, tmp))]


def sizes(paths: list[Path]) -> str:
    return ", ".join(f"{p} ({p.stat().st_size / 1024:.0f} KiB)" for p in paths)


def add_arguments(parser) -> None:
    """``train-relations``' flags."""
    from .relations import DURATION, TRAIN_SEED

    parser.add_argument("--seeds", type=int, default=20, help=f"training seeds, from {TRAIN_SEED} (default 20)")
    parser.add_argument("--duration", type=float, default=DURATION,
                        help=f"s of each airport run (default {DURATION:g})")
    workers.add_arguments(parser)
    add_models_out_argument(parser, "pipeline/groups/models/")


def main(args) -> int:
    """``crowdsim experiment train-relations``."""
    from pipeline.groups.relations import MODELS_DIR

    from ..cli import check_duration
    from .relations import TRAIN_SEED, save_models, train

    check_duration(args)
    out = training_seeds_out(args, 20, TRAIN_SEED)
    t0 = time.perf_counter()
    models = train(args.seeds, args.duration, engine=Engine(args.workers, args.ray))
    paths = saved(models, save_models, out, MODELS_DIR)
    info = next(iter(models.values()))[1]
    print(f"{info['pairs']} pairs of tracks ({info['related']} related) from seeds {info['train_seeds'][0]}-"
          f"{info['train_seeds'][1]}; {time.perf_counter() - t0:.0f} s; models: " + sizes(paths))
    return 0

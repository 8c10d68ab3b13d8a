"""crowdsim: a synthetic-crowd testbed for people perception and social robot navigation.

The public face: ``crowdsim.Simulation``, ``load_scenario``, ``build_pipeline``, the scoring functions, the data
types and ``Error``, the base of every error a user can cause. The names are imported on first use (PEP 562), so
that ``import crowdsim`` costs what registering the gymnasium environments costs, not the simulator's import.
"""

from importlib import import_module

__version__ = "0.1.0"

from . import envs  # noqa: E402,F401  (registers the gymnasium environments)

_TYPES = ("LaserScan", "DepthFrame", "CameraFrame", "Visibility", "GroundTruthTags", "DetectedPersons",
          "TrackedPersons", "TagReading", "SocialRelations", "TrackedGroups")
# name -> the module that defines it
_WHERE = {
    "Error": "crowdsim.errors",
    "Simulation": "crowdsim.loop", "Frame": "crowdsim.loop",
    "load_scenario": "scenarios.loader",
    "build_pipeline": "pipeline.assemble",
    **{name: "pipeline.types" for name in _TYPES},
    "score_tracking": "evaluation.score",  # a run's files or sequences: CLEAR-MOT, IDF1, HOTA, OSPA
    "evaluate": "evaluation.clearmot",  # CLEAR-MOT of two sequences in memory
    "hota": "evaluation.hota", "ospa": "evaluation.ospa",
    "Sequence": "evaluation.sequence", "CsvPair": "evaluation.stream", "SequencePair": "evaluation.stream",
    "score_groups": "evaluation.group_score",
    "navigation_metrics": "evaluation.navigation", "read_nav_run": "evaluation.navigation",
}
__all__ = list(_WHERE)


def __getattr__(name: str):
    if name in _WHERE:
        value = getattr(import_module(_WHERE[name]), name)
        globals()[name] = value  # looked up once
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})

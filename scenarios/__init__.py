"""Scenario files (YAML), the bundled scenarios, and the code that loads and validates them.

The names are imported on first use (PEP 562): the format gathers the parts' declared parameters, and some of those
parts (the robot's drivers) use the schema's kinds, so importing ``scenarios.schema`` must not load the format.
"""

from importlib import import_module

_WHERE = {"ScenarioError": "scenarios.schema", "bundled_scenarios": "scenarios.loader",
          "load_scenario": "scenarios.loader", "scenario_from_dict": "scenarios.loader",
          "wall_segments": "scenarios.geometry"}
__all__ = sorted(_WHERE)


def __getattr__(name: str):
    if name in _WHERE:
        value = getattr(import_module(_WHERE[name]), name)
        globals()[name] = value  # looked up once
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})

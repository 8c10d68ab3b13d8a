"""Scenario files (YAML), the bundled scenarios, and the code that loads and validates them."""

from .geometry import wall_segments
from .loader import bundled_scenarios, load_scenario, scenario_from_dict
from .schema import ScenarioError

__all__ = ["ScenarioError", "bundled_scenarios", "load_scenario", "scenario_from_dict", "wall_segments"]

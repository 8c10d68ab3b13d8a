"""The packages' dependencies point one way (ARCHITECTURE.md): ``pipeline`` and ``evaluation`` run on a real robot's
data, so they never import the simulator (``crowdsim``) or its sensors; ``sensors`` never imports ``crowdsim``;
``scenarios`` imports only the parts whose declared parameters make up the scenario format (``pipeline``, ``sensors``,
and the robot's body and drivers, ``crowdsim.robot`` and ``crowdsim.drivers``, which import no more of the
simulator), never the simulator or the evaluation."""

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
FORBIDDEN = {"pipeline": {"crowdsim", "sensors"}, "evaluation": {"crowdsim", "sensors"}, "sensors": {"crowdsim"},
             "scenarios": {"crowdsim", "evaluation"}}
ALLOWED = {"scenarios": {"crowdsim.robot", "crowdsim.drivers"}}  # modules a package may import from a package it may not


def imported_packages(path: Path, allowed: set[str] = frozenset()) -> set[str]:
    """Top-level packages a module imports (anywhere in it, function bodies included), but for the modules
    ``allowed``; relative imports stay inside the package and are left out."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        names = ([alias.name for alias in node.names] if isinstance(node, ast.Import)
                 else [node.module] if isinstance(node, ast.ImportFrom) and node.level == 0 else [])
        found |= {name.split(".")[0] for name in names if name not in allowed}
    return found


@pytest.mark.parametrize("package", sorted(FORBIDDEN))
def test_no_module_imports_against_the_direction_of_the_layout(package):
    modules = sorted((ROOT / package).rglob("*.py"))
    assert modules
    wrong = {str(m.relative_to(ROOT)): sorted(imported_packages(m, ALLOWED.get(package, set())) & FORBIDDEN[package])
             for m in modules}
    assert {m: w for m, w in wrong.items() if w} == {}


def test_the_check_sees_an_import_inside_a_function(tmp_path):
    module = tmp_path / "m.py"
    module.write_text("def f():\n    from crowdsim.loop import Simulation\n    import sensors.laser\n")
    assert imported_packages(module) == {"crowdsim", "sensors"}


def test_the_simulator_modules_the_format_imports_import_no_more_of_it():
    for module in ALLOWED["scenarios"]:
        path = ROOT / (module.replace(".", "/") + ".py")
        assert imported_packages(path) & {"crowdsim", "sensors", "evaluation"} == set()


def test_each_module_of_the_formats_import_cycle_imports_first():
    # the format imports the drivers, which use the schema's kinds: whichever a user imports first, it loads
    import subprocess
    import sys

    modules = ["crowdsim.drivers", "crowdsim.robot", "scenarios.schema", "scenarios.format", "pipeline.assemble",
               "pipeline.software", "scenarios"]
    runs = {m: subprocess.Popen([sys.executable, "-c", f"import {m}"], cwd=ROOT, stderr=subprocess.PIPE, text=True)
            for m in modules}
    failed = {m: run.communicate()[1].strip().splitlines()[-1:] for m, run in runs.items() if run.wait() != 0}
    assert failed == {}

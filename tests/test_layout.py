"""The packages' dependencies point one way (ARCHITECTURE.md): ``pipeline`` and ``evaluation`` run on a real robot's
data, so they never import the simulator (``crowdsim``) or its sensors; ``sensors`` never imports ``crowdsim``;
``scenarios`` imports only the parts whose declared parameters make up the scenario format (``pipeline`` and
``sensors``), never the simulator or the evaluation."""

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
FORBIDDEN = {"pipeline": {"crowdsim", "sensors"}, "evaluation": {"crowdsim", "sensors"}, "sensors": {"crowdsim"},
             "scenarios": {"crowdsim", "evaluation"}}


def imported_packages(path: Path) -> set[str]:
    """Top-level packages a module imports (anywhere in it, function bodies included); relative imports stay
    inside the package and are left out."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found |= {alias.name.split(".")[0] for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0:
            found.add(node.module.split(".")[0])
    return found


@pytest.mark.parametrize("package", sorted(FORBIDDEN))
def test_no_module_imports_against_the_direction_of_the_layout(package):
    modules = sorted((ROOT / package).rglob("*.py"))
    assert modules
    wrong = {str(m.relative_to(ROOT)): sorted(imported_packages(m) & FORBIDDEN[package]) for m in modules}
    assert {m: w for m, w in wrong.items() if w} == {}


def test_the_check_sees_an_import_inside_a_function(tmp_path):
    module = tmp_path / "m.py"
    module.write_text("def f():\n    from crowdsim.loop import Simulation\n    import sensors.laser\n")
    assert imported_packages(module) == {"crowdsim", "sensors"}

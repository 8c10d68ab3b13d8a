"""``crowdsim validate`` at its quick size: the RiMEA acceptance criteria, the report, and the checkers themselves.

One quick run of every check (module fixture, about 15 s on two cores) serves the acceptance tests; the helpers
(Weidmann's curve, the disc placement, the wall watch) are tested alone on cases with known answers.
"""

import json

import numpy as np
import pytest

from crowdsim.crowd import validation as V

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("validation")
    return out, V.run_validation(out, quick=True, progress=False)


def check(results, name):
    return next(c for c in results["checks"] if c["name"] == name)


# -- the checkers ------------------------------------------------------------------------------------------------


def test_weidmann_curve():
    assert V.weidmann(5.4) == pytest.approx(0.0, abs=1e-12)
    assert V.weidmann(1.0) == pytest.approx(1.34 * (1 - np.exp(-1.913 * (1 - 1 / 5.4))))
    v = V.weidmann([0.5, 1, 2, 3, 4])
    assert np.all(np.diff(v) < 0) and v[0] < 1.34


def test_discs_are_placed_without_overlap_up_to_dense_packing():
    # 4 persons/m^2 of 0.25 m discs (area fraction 0.79) fits; the placement keeps every centre in the box
    rng = np.random.default_rng(0)
    sample, outside = V._box([0.25, 0.25], [9.75, 9.75])
    pos = V.place_discs(rng, 400, 0.25, sample, outside)
    assert pos is not None
    d = np.linalg.norm(pos[:, None] - pos[None], axis=-1) + np.eye(len(pos)) * 9
    assert d.min() >= 0.5
    assert pos.min() >= 0.25 - 1e-3 and pos.max() <= 9.75 + 1e-3


def test_ring_reports_densities_beyond_close_packing():
    run = V.ring_run(5.0, quick=True)
    assert not run["set_up"] and "densest packing" in run["why"]


def test_watch_sees_a_body_in_a_wall_and_an_overlap():
    walls = np.array([[[0.0, 0.0], [10.0, 0.0]], [[10.0, 0.0], [10.0, 10.0]]])
    region = V.Region(np.array([[0, 0], [10, 0], [10, 10], [0, 10]], float))

    class Snapshot:
        pos = np.array([[5.0, 0.2], [5.3, 5.0], [5.7, 5.0], [11.0, 5.0]])
        radius = np.full(4, 0.25)

    watch = V.Watch(walls, region)
    watch(Snapshot)
    assert watch.inside_wall == 1  # 0.05 m into the floor's wall
    assert watch.wrong_side == 1  # 1 m beyond the wall at x = 10: clear of it, but on its far side
    assert watch.max_overlap == pytest.approx(0.1)
    assert watch.min_clearance == pytest.approx(-0.05)
    assert not watch.ok


# -- the acceptance criteria, at the quick size ------------------------------------------------------------------


def test_rimea1_corridor_time(quick_run):
    c = check(quick_run[1], "RiMEA 1")
    assert 26.0 <= c["values"]["walking_time_s"] <= 34.0
    assert c["passed"]


@pytest.mark.parametrize("density", [0.5, 1.0, 2.0, 3.0])
def test_rimea4_speed_within_25_percent_of_weidmann(quick_run, density):
    runs = check(quick_run[1], "RiMEA 4 / Weidmann")["values"]["runs"]
    run = next(r for r in runs if r["density_target"] == density)
    assert run["set_up"]
    assert abs(run["density"] - density) < 0.02
    assert abs(run["relative_error"]) <= 0.25, (
        f"{run['speed_m_s']:.2f} m/s at {density:g} persons/m^2, Weidmann {run['weidmann_m_s']:.2f} m/s")


def test_rimea6_nobody_crosses_a_wall(quick_run):
    c = check(quick_run[1], "RiMEA 6")
    s = c["safety"]
    assert s["body_steps_inside_wall"] == 0 and s["body_steps_wrong_side"] == 0
    assert s["min_wall_clearance_m"] >= -1e-9
    assert s["steps_checked"] > 100
    assert c["values"]["arrived"] == 20
    assert c["passed"]


def test_rimea7_every_speed_within_its_types_range(quick_run):
    c = check(quick_run[1], "RiMEA 7")
    assert set(c["values"]) == {"adult", "child", "elder"}
    for name, r in c["values"].items():
        p = r["configured"]
        speeds = np.array(r["speeds_m_s"])
        assert len(speeds) == r["n"] >= 20
        assert speeds.min() >= p["speed_min"] - 1e-3 and speeds.max() <= p["speed_max"] + 1e-3, name
        assert abs(speeds.mean() - p["speed_mean"]) <= 3 * p["speed_std"] / np.sqrt(len(speeds)), name
    assert c["passed"]


def test_bottleneck_flow_grows_with_width(quick_run):
    runs = check(quick_run[1], "Bottleneck")["values"]["runs"]
    widths = [r["width_m"] for r in runs]
    flows = [r["flow_p_s"] for r in runs]
    assert len(widths) >= 2 and widths == sorted(widths)
    assert all(b > a for a, b in zip(flows, flows[1:])), dict(zip(widths, flows))
    # nobody is left clogged before the narrowest door
    assert all(r["crossed"] == r["agents"] for r in runs), {r["width_m"]: r["crossed"] for r in runs}


def test_no_body_inside_a_wall_in_any_run(quick_run):
    s = quick_run[1]["safety"]
    assert s["walls_ok"] and s["body_steps_inside_wall"] == 0 and s["body_steps_wrong_side"] == 0
    assert 0.0 <= s["max_overlap_m"] < 0.25  # reported; bodies never pass halfway through each other


def test_report_names_every_test_and_links_real_pngs(quick_run):
    out, results = quick_run
    report = (out / "report.md").read_text()
    for name in ("RiMEA 1", "RiMEA 4 / Weidmann", "RiMEA 6", "RiMEA 7", "Bottleneck", "Overlap", "Walls"):
        assert f"| {name}" in report
    plots = [c["plot"] for c in results["checks"]]
    assert len(plots) == 5
    for plot in plots:
        assert f"]({plot})" in report
        assert (out / plot).read_bytes()[:8] == PNG_MAGIC
    saved = json.loads((out / "validation.json").read_text())
    assert saved["quick"] is True and [c["name"] for c in saved["checks"]] == [c["name"] for c in results["checks"]]
    assert "max_overlap_m" in saved["safety"]

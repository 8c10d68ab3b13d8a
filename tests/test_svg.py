"""The SVG top-down view: parsed back with xml.etree; expected coordinates are worked out by hand in comments.

The transform under test: a point (x, y) m is drawn at (100 x, -100 y) user units.
"""

import re
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from evaluation.svg import write_svg

NS = "{http://www.w3.org/2000/svg}"


def track(i, ts, xs, ys, vx=0.0, vy=0.0):
    """Rows (frame, t, id, x, y, vx, vy) of one track; frame = index."""
    n = len(ts)
    return np.column_stack([np.arange(n), ts, np.full(n, i), xs, ys, np.full(n, vx), np.full(n, vy)])


def draw(tmp_path, **kw):
    path = tmp_path / "run.svg"
    kw.setdefault("tracks", None)
    write_svg(path, **kw)
    return ET.parse(path).getroot()


def layer(root, name):
    (g,) = [e for e in root.iter() if e.get("id") == name]
    return g


def points(el):
    return np.array([[float(v) for v in p.split(",")] for p in el.get("points").split()])


def subpaths(d):
    """Vertices of each subpath of path data made of M (absolute), L (absolute), l (relative) and z."""
    out, pos, cmd = [], None, None
    for tok in re.findall(r"[MLlz]|-?\d+(?:\.\d+)?", d):
        if tok in "MLlz":
            cmd = tok
            continue
        if pos is None:
            pos = [float(tok)]
            continue
        pos.append(float(tok))
        p = np.array(pos)
        pos = None
        if cmd == "M":
            out.append([p])
            cmd = "L"  # further pairs after M are lines
        elif cmd == "L":
            out[-1].append(p)
        else:
            out[-1].append(out[-1][-1] + p)
    return [np.array(s) for s in out]


def texts(g):
    return ["".join(t.itertext()).strip() for t in g.iter(NS + "text")]


def sets(el):
    return [s for s in el if s.tag == NS + "set"]


def test_output_is_svg_xml_with_viewbox_size_and_title(tmp_path):
    tr = track(1, [0.0, 1.0], [1.0, 3.0], [2.0, 2.0])
    root = draw(tmp_path, tracks=tr, title="run <1> & co")
    assert root.tag == NS + "svg"
    x0, y0, w, h = map(float, root.get("viewBox").split())
    # data x 1..3 m, y = 2 m: x0 = 100 - 100 margin; y0 = -200 - 100 margin - 100 title band;
    # w = 200 + 2 * 100; h = 0 + 2 * 100 + 100 + 100 (scale band)
    assert (x0, y0, w, h) == (0.0, -400.0, 400.0, 400.0)
    assert (root.get("width"), root.get("height")) == ("120", "120")  # 0.3 px per user unit
    assert texts(layer(root, "title")) == ["run <1> & co"]


def test_track_is_a_polyline_of_its_positions_in_time_order_with_its_id_at_both_ends(tmp_path):
    a = track(7, [0.0, 0.5, 1.0], [1.0, 1.5, 2.0], [2.0, 2.25, 2.5])
    b = track(8, [0.0, 1.0], [0.0, 0.0], [0.0, -1.0])
    rows = np.concatenate([a, b])[[3, 2, 0, 4, 1]]  # shuffled: drawn in time order all the same
    tracks = layer(draw(tmp_path, tracks=rows, animate=False), "tracks")
    groups = {texts(g)[0]: g for g in tracks if g.tag == NS + "g"}
    assert sorted(groups) == ["7", "8"]
    (line,) = groups["7"].iter(NS + "polyline")
    # (1, 2) -> (100, -200); (1.5, 2.25) -> (150, -225); (2, 2.5) -> (200, -250)
    np.testing.assert_allclose(points(line), [[100, -200], [150, -225], [200, -250]])
    np.testing.assert_allclose(points(next(groups["8"].iter(NS + "polyline"))), [[0, 0], [0, 100]])
    start, end = list(groups["7"].iter(NS + "text"))
    assert texts(groups["7"]) == ["7", "7"]
    # written 10 units right of and above the first and the last point
    assert (start.get("x"), start.get("y"), end.get("x"), end.get("y")) == ("110", "-210", "210", "-260")
    assert groups["7"].get("stroke") != groups["8"].get("stroke")


def test_velocity_arrows_every_second_with_length_of_half_a_second_of_motion(tmp_path):
    ts = np.arange(0.0, 2.51, 0.25)
    moving = track(1, ts, ts * 1.0, np.zeros(ts.size), vx=1.0)  # 1 m/s along x
    still = track(2, ts, np.full(ts.size, 5.0), np.full(ts.size, 5.0))
    groups = [g for g in layer(draw(tmp_path, tracks=np.concatenate([moving, still])), "tracks")]
    arrows = [subpaths(next(g.iter(NS + "path")).get("d")) for g in groups]
    assert arrows[1] == []  # at rest: no direction, no arrow
    lines, heads = arrows[0][0::2], arrows[0][1::2]
    # rows at t = 0, 1, 2 s: x = 0, 1, 2 m; the line reaches 0.5 s * 1 m/s = 50 units further
    np.testing.assert_allclose([ln[0] for ln in lines], [[0, 0], [100, 0], [200, 0]])
    np.testing.assert_allclose([ln[1] for ln in lines], [[50, 0], [150, 0], [250, 0]])
    # the head: barbs 15 cm long, 25 degrees off the line back from the tip, the first one turned counterclockwise
    # in the world (y down on screen)
    c, s = 15 * np.cos(np.radians(25)), 15 * np.sin(np.radians(25))
    np.testing.assert_allclose(heads[0], [[50 - c, s], [50, 0], [50 - c, -s]], atol=0.051)


def test_detection_is_a_diamond_at_its_position_with_id_and_time(tmp_path):
    det = np.array([[3, 4.25, 5, 2.0, -1.0], [3, 4.25, 6, -1.0, 0.5]])
    root = draw(tmp_path, tracks=None, detections=det, animate=False)
    (frame,) = [g for g in layer(root, "detections") if g.tag == NS + "g"]
    diamonds = subpaths(frame.find(NS + "path").get("d"))
    # (2, -1) m -> (200, 100): top, right, bottom, left vertices 3 units from the centre
    np.testing.assert_allclose(diamonds[0], [[200, 97], [203, 100], [200, 103], [197, 100]])
    np.testing.assert_allclose(diamonds[1].mean(0), [-100, -50])
    labels = list(layer(root, "detection-labels").iter(NS + "text"))
    assert texts(layer(root, "detection-labels")) == ["5 4.25", "6 4.25"]
    # first frame: no step to turn across, so horizontal, starting 4.5 right of and 1.5 below the centre
    tx, ty, angle = map(float, re.fullmatch(r"translate\((\S+) (\S+)\)rotate\((\S+)\)",
                                            labels[0].get("transform")).groups())
    assert angle == 0.0
    assert abs(tx - 204.5) <= 0.5 and abs(ty - 101.5) <= 0.5


@pytest.mark.parametrize("step, angle", [((0.05, 0.0), -90.0), ((0.0, 0.05), 0.0), ((0.05, 0.05), 45.0)])
def test_detection_labels_turn_across_the_step_from_the_frame_before(tmp_path, step, angle):
    det = np.array([[0, 0.0, 1, 0.0, 0.0], [1, 0.04, 1, *step], [1, 0.04, 2, 9.0, 9.0]])
    labels = list(layer(draw(tmp_path, tracks=None, detections=det), "detection-labels").iter(NS + "text"))
    angles = [float(re.search(r"rotate\((\S+)\)", t.get("transform")).group(1)) for t in labels]
    # a step along x gets a vertical label (-90: read upwards, never upside down); a step along y a horizontal one;
    # a step up and right (on screen too) one going down and right (45). Person 2 has no one within 0.5 m before.
    assert angles == [0.0, angle, 0.0]


def test_time_window_drops_rows_outside_it(tmp_path):
    ts = np.arange(0.0, 10.5, 1.0)  # t = 0 .. 10 s, x = t m
    tr = track(1, ts, ts, np.zeros(ts.size))
    gt = track(2, ts, ts, np.ones(ts.size))
    det = np.column_stack([ts, ts, np.zeros(ts.size), ts, np.full(ts.size, 2.0)])
    robot = np.column_stack([ts, ts, np.full(ts.size, 3.0)])
    root = draw(tmp_path, tracks=tr, groundtruth=gt, detections=det, robot=robot, start=2.5, end=5.0)
    # t = 3, 4, 5 s are in [2.5, 5]
    np.testing.assert_allclose(points(next(layer(root, "tracks").iter(NS + "polyline")))[:, 0], [300, 400, 500])
    np.testing.assert_allclose(points(next(layer(root, "groundtruth").iter(NS + "polyline")))[:, 0], [300, 400, 500])
    np.testing.assert_allclose(points(next(layer(root, "robot").iter(NS + "polyline")))[:, 0], [300, 400, 500])
    assert texts(layer(root, "detection-labels")) == ["0 3.00", "0 4.00", "0 5.00"]
    clock = texts(layer(root, "clock"))
    assert (clock[0], clock[-1], len(clock)) == ("2.5 s", "5.0 s", 26)  # 0.1 s steps over 2.5 s


def test_animation_begins_at_the_rows_times_relative_to_the_window_start(tmp_path):
    ts = np.arange(2.5, 4.6, 0.5)  # a track from 2.5 to 4.5 s; frames 0.5 s apart
    tr = track(4, ts, ts, np.zeros(ts.size))
    det = np.array([[0, 3.0, 0, 1.0, 1.0], [1, 3.5, 0, 1.0, 1.0]])
    root = draw(tmp_path, tracks=tr, detections=det, start=2.0, end=6.0)
    for name in ("detections", "detection-labels"):
        frames = [g for g in layer(root, name) if g.tag == NS + "g"]
        assert [g.get("display") for g in frames] == ["none", "none"]
        # each frame shows at t - start for 1 s, and again from the window's end (6 - 2 = 4 s) for good
        assert [[(s.get("begin"), s.get("dur"), s.get("fill")) for s in sets(g)] for g in frames] == [
            [("1.000s", "1.000s", None), ("4.000s", None, "freeze")],
            [("1.500s", "1.000s", None), ("4.000s", None, "freeze")]]
    (marker,) = [g for g in layer(root, "markers") if texts(g) == ["4"]]
    (show,) = sets(marker)
    motion = marker.find(NS + "animateMotion")
    # from 2.5 - 2 = 0.5 s for (4.5 - 2.5) + one frame (0.5 s) = 2.5 s
    assert (show.get("begin"), show.get("dur")) == ("0.500s", "2.500s")
    assert (motion.get("begin"), motion.get("dur"), motion.get("calcMode")) == ("0.500s", "2.500s", "linear")
    values = np.array([[float(v) for v in p.split(",")] for p in motion.get("values").split(";")])
    # sampled every 0.2 s over 2.5 s: 14 values 2.5 / 13 s apart; x = t m, held at the last row for the last frame
    ts_sampled = np.linspace(2.5, 5.0, 14)
    np.testing.assert_allclose(values[:, 0], 100 * np.minimum(ts_sampled, 4.5), atol=0.051)
    clock = [t for t in layer(root, "clock") if t.tag == NS + "text"]
    assert [sets(t)[0].get("begin") for t in clock[:3]] == ["0.000s", "0.100s", "0.200s"]
    # 0 .. 4 s in 0.1 s steps: 41 texts, the last one held at the end
    assert (len(clock), "".join(clock[-1].itertext()), sets(clock[-1])[0].get("fill")) == (41, "6.0 s", "freeze")


def test_static_view_has_no_animation_and_shows_everything(tmp_path):
    tr = track(1, [0.0, 1.0], [0.0, 1.0], [0.0, 0.0])
    det = np.array([[0, 0.0, 0, 1.0, 1.0]])
    root = draw(tmp_path, tracks=tr, detections=det, robot=np.array([[0.0, 0.0, 0.0]]), animate=False, start=0.0)
    tags = {e.tag for e in root.iter()}
    assert not tags & {NS + "set", NS + "animateMotion", NS + "animate"}
    assert all(e.get("display") is None for e in root.iter())
    assert texts(layer(root, "clock")) == ["0.0 to 1.0 s"]


def test_walls_ground_truth_and_robot_are_drawn(tmp_path):
    walls = np.array([[[0.0, 0.0], [3.0, 0.0]], [[3.0, 0.0], [3.0, 4.0]]])
    gt = track(9, [0.0, 1.0], [1.0, 2.0], [1.0, 1.0])
    robot = np.array([[1.0, 0.5, 0.5], [0.0, 0.0, 0.5]])  # out of time order
    root = draw(tmp_path, tracks=track(1, [0.0], [1.0], [1.0]), groundtruth=gt, robot=robot, walls=walls)
    lines = [[float(ln.get(k)) for k in ("x1", "y1", "x2", "y2")] for ln in layer(root, "walls")]
    assert lines == [[0, 0, 300, 0], [300, 0, 300, -400]]
    g = layer(root, "groundtruth")
    np.testing.assert_allclose(points(g.find(NS + "polyline")), [[100, -100], [200, -100]])
    assert g.get("stroke") == "#999"  # grey, thinner than the tracks
    assert float(g.get("stroke-width")) < float(layer(root, "tracks").get("stroke-width"))
    r = layer(root, "robot")
    np.testing.assert_allclose(points(r.find(NS + "polyline")), [[0, -50], [50, -50]])
    assert r.get("stroke") == "#bbb"


def test_scale_bar_is_a_round_number_of_metres(tmp_path):
    # data 10 m wide -> view 12 m; a quarter is 3 m -> the bar is 2 m = 200 units
    root = draw(tmp_path, tracks=track(1, [0.0, 1.0], [0.0, 10.0], [0.0, 0.0]))
    scale = layer(root, "scale")
    d = scale.find(NS + "path").get("d")
    xs = [float(v) for v in re.findall(r"[MH](-?[\d.]+)", d)]
    assert xs[1] - xs[0] == pytest.approx(200.0)
    assert texts(scale) == ["2 m"]


def test_bad_input_is_refused(tmp_path):
    with pytest.raises(ValueError, match="tracks"):
        write_svg(tmp_path / "x.svg", tracks=np.zeros((3, 5)))
    with pytest.raises(ValueError, match="before start"):
        write_svg(tmp_path / "x.svg", tracks=track(1, [0.0], [0.0], [0.0]), start=2.0, end=1.0)


def test_what_does_not_move_is_one_layer_apart_from_what_does(tmp_path):
    tr = track(1, [0.0, 1.0], [0.0, 1.0], [0.0, 0.0])
    det = np.array([[0, 0.0, 0, 1.0, 1.0]])
    kw = dict(tracks=tr, groundtruth=tr, detections=det, robot=np.array([[0.0, 0.0, 0.0]]), walls=np.zeros((1, 2, 2)))
    root = draw(tmp_path, **kw)
    top = [e.get("id") for e in root][1:]  # after the background
    assert top == ["map", "groups", "detections", "detection-labels", "markers", "clock", "scale", "title"]
    # Chrome paints a will-change layer once instead of at every step of every marker
    assert layer(root, "map").get("style") == "will-change:transform"
    assert [e.get("id") for e in layer(root, "map")] == ["walls", "robot", "groundtruth", "tracks"]
    assert layer(draw(tmp_path, animate=False, **kw), "map").get("style") is None


def two_walking_together():
    """Tracks 1 and 2 side by side 1 m apart, frames 0 and 1 at t = 0 and 0.5 s, a third (9) alone far off; group 5
    of 1 and 2 in both frames, its centroid between them; rows as groups.csv holds them (frame, t, group, id, x, y,
    age)."""
    tr = np.concatenate([track(1, [0.0, 0.5], [1.0, 1.5], [1.0, 1.0]), track(2, [0.0, 0.5], [1.0, 1.5], [2.0, 2.0]),
                         track(9, [0.0, 0.5], [6.0, 6.0], [0.0, 0.0])])
    groups = np.array([[0, 0.0, 5, 1, 1.0, 1.5, 0.0], [0, 0.0, 5, 2, 1.0, 1.5, 0.0],
                       [1, 0.5, 5, 1, 1.5, 1.5, 0.5], [1, 0.5, 5, 2, 1.5, 1.5, 0.5]])
    return tr, groups


def test_group_members_are_joined_to_the_centroid_with_the_group_id_there_frame_by_frame(tmp_path):
    tr, groups = two_walking_together()
    root = draw(tmp_path, tracks=tr, groups=groups, start=0.0)
    frames = [g for g in layer(root, "groups") if g.tag == NS + "g"]
    assert [g.get("display") for g in frames] == ["none", "none"]
    # frame 0: members (1, 1) and (1, 2) m -> (100, -100) and (100, -200); centroid (1, 1.5) -> (100, -150);
    # frame 1: all 0.5 m further along x
    for g, x in zip(frames, (100.0, 150.0)):
        (path,) = g.iter(NS + "path")
        lines = subpaths(path.get("d"))
        np.testing.assert_allclose(lines, [[[x, -100], [x, -150]], [[x, -200], [x, -150]]])
        (label,) = g.iter(NS + "text")
        assert (texts(g), float(label.get("x")), float(label.get("y"))) == (["G5"], x, -150.0)
        assert path.get("stroke") == label.get("fill") == "hsl(328,75%,40%)"  # group 5's colour: 5 * 137.508 % 360
    # each frame from its time until the next; the last one stays on at the end
    assert [[(s.get("begin"), s.get("dur"), s.get("fill")) for s in sets(g)] for g in frames] == [
        [("0.000s", "0.500s", None)], [("0.500s", None, "freeze")]]


def test_group_layer_is_above_the_tracks_and_below_the_detection_labels(tmp_path):
    tr, groups = two_walking_together()
    det = np.array([[0, 0.0, 0, 1.0, 1.0]])
    root = draw(tmp_path, tracks=tr, groups=groups, detections=det)
    top = [e.get("id") for e in root]
    assert top.index("map") < top.index("groups") < top.index("detection-labels")


def test_static_view_draws_the_groups_of_the_last_frame_only(tmp_path):
    tr, groups = two_walking_together()
    root = draw(tmp_path, tracks=tr, groups=groups, animate=False)
    (frame,) = [g for g in layer(root, "groups") if g.tag == NS + "g"]
    assert frame.get("display") is None and not sets(frame)
    # frame 1 (t = 0.5 s): members at (1.5, 1) and (1.5, 2) m, centroid (1.5, 1.5) m
    np.testing.assert_allclose(subpaths(frame.find(NS + "path").get("d")),
                               [[[150, -100], [150, -150]], [[150, -200], [150, -150]]])
    label = frame.find(NS + "text")
    assert (texts(frame), label.get("x"), label.get("y")) == (["G5"], "150.0", "-150.0")


def test_group_members_are_found_by_frame_and_id_and_those_without_a_track_row_left_out(tmp_path):
    # track 1 in frames 0 and 1; track 2 only in frame 0; group 3 lists both in frame 1 (rows without the age
    # column). Members are matched by frame and track id, whatever the rows' order
    tr = np.concatenate([track(1, [0.0, 0.5], [0.0, 1.0], [0.0, 0.0]), track(2, [0.0], [5.0], [5.0])])[[2, 1, 0]]
    groups = np.array([[1, 0.5, 3, 2, 2.0, 2.0], [1, 0.5, 3, 1, 2.0, 2.0]])
    frame = layer(draw(tmp_path, tracks=tr, groups=groups, animate=False), "groups").find(NS + "g")
    # only track 1's row of frame 1, (1, 0) m -> (100, 0), joined to the centroid (2, 2) m -> (200, -200)
    np.testing.assert_allclose(subpaths(frame.find(NS + "path").get("d")), [[[100, 0], [200, -200]]])
    assert texts(frame) == ["G3"]


def test_groups_layer_shows_a_cycle_at_most_every_0_2_s_back_from_the_last(tmp_path):
    ts = np.arange(26) * 0.04  # 25 Hz from 0 to 1 s
    tr = np.concatenate([track(1, ts, ts, np.zeros(26)), track(2, ts, ts, np.ones(26))])
    groups = np.concatenate([np.column_stack([np.arange(26), ts, np.full(26, 4), np.full(26, i), ts, np.full(26, 0.5)])
                             for i in (1, 2)])
    root = draw(tmp_path, tracks=tr, groups=groups, start=0.0)
    frames = [g for g in layer(root, "groups") if g.tag == NS + "g"]
    # the cycles at 1.0, 0.8, ..., 0.0 s: six of the 26, each until the next, the last for good
    assert [[(s.get("begin"), s.get("dur")) for s in sets(g)] for g in frames] == [
        [(f"{b:.3f}s", "0.200s")] for b in (0.0, 0.2, 0.4, 0.6, 0.8)] + [[("1.000s", None)]]
    # the 0.4 s cycle's centroid is at x = 0.4 m
    assert frames[2].find(NS + "text").get("x") == "40.0"


def test_groups_outside_the_window_are_left_out(tmp_path):
    tr, groups = two_walking_together()
    root = draw(tmp_path, tracks=tr, groups=groups, end=0.25)
    (frame,) = [g for g in layer(root, "groups") if g.tag == NS + "g"]
    assert frame.find(NS + "text").get("x") == "100.0"  # frame 0's centroid; frame 1 at 0.5 s is after the end
    assert [(s.get("begin"), s.get("dur")) for s in sets(frame)] == [("0.000s", None)]


def test_bad_groups_are_refused(tmp_path):
    with pytest.raises(ValueError, match="groups"):
        write_svg(tmp_path / "x.svg", tracks=None, groups=np.zeros((2, 5)))

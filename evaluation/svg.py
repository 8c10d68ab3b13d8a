"""An animated SVG top-down view of a tracking run, after SPENCER's ``srl_tracking_exporter`` (seed 000, Sec. 7.3).

Why: a PNG cannot be zoomed into to see why a track's id switched; a vector graphic can, down to the single
detections, whose ids and timestamps are written beside them in text too small to see at full view (seed 000,
Fig. 12). Optionally animated with SMIL (no JavaScript), so the file is all a browser needs.

Transform: 1 m = 100 user units, x right and y up: a point (x, y) in metres is drawn at (100 x, -100 y), written
with one decimal (1 mm). The viewBox frames the data and the walls with a 1 m margin, plus a band above for the
title and the clock and one below for the scale bar; at 100 % zoom 1 m is 30 px, at a browser's 500 % 150 px.

Drawn, bottom to top: walls; the robot's odometry (wide, light grey); the ground truth (thin, grey); each track as
a polyline in a colour of its id, with the id at its start and end and a velocity arrow every 1 s (a line from the
position to where the velocity leads in 0.5 s, with a head: its length is the speed); the tracked groups
(groups.csv), each a line from every member's position (its track's row of the same cycle) to the group's centroid
in a colour of the group's id, with "G<id>" at the centroid: when animated those of each cycle in turn, else those
of the window's last cycle; detections as small diamonds; their "id time" labels, in a layer of their own above all
diamonds; when animated, a marker per ground-truth person, the robot and each track (with its id), and the clock;
the scale bar and the title. At 25 Hz a walking person's detections are 5 cm apart and a label 12 cm long, so each
label is turned across the step from the nearest detection of the frame before: a person's labels stack like the
rungs of a ladder, each one readable.

Animation: the trajectories are drawn whole from the start, as the map of the window; what moves is
  * a marker per track, ground-truth person and the robot: one <animateMotion> from the first row to one frame
    after the last, positions sampled every 0.2 s (no keyTimes: 5x smaller than one key per 25 Hz row);
  * the detections of each frame, shown from their time for 1 s (a trail), one <set> per frame and layer;
  * the groups of a tracking cycle, shown from its time until the next cycle drawn, one <set> per cycle; the
    cycles are sampled as the markers are, at most every 0.2 s (counted back from the last cycle, which is always
    drawn and stays on at the end): at most 5 a second instead of 12.5 keeps a 120 s run with 10 groups of 3 a
    cycle to about 1 MB;
  * a clock in 0.1 s steps.
Every animation begins at its rows' time minus the window's start; it plays once and holds at the end, where every
detection is shown, so the last frame is the whole window to zoom into (with the groups of its last cycle). Why
this design: the work of an animation frame stays bounded however long the window, since the browser has only the
animations now active to update (markers alive, the last second of detections, one cycle's groups) and only what is
shown to paint; what is not shown yet is display:none, not even laid out. The SPENCER exporter's way, every element
fading in and staying, makes each frame cost more than the last: in headless Chromium (software raster) a 30 s
window of 80 people played at 28 frames/s throughout, and at 20, 6 and 2 frames/s after 2, 14 and 25 s when the
detections stay on.
"""

from __future__ import annotations

from xml.sax.saxutils import escape

import numpy as np
from scipy.spatial.distance import cdist

__all__ = ["write_svg"]

UNITS_PER_M = 100.0
PX_PER_UNIT = 0.3  # 30 px per metre at 100 % zoom
ARROW_EVERY_S = 1.0
ARROW_LEAD_S = 0.5  # a velocity arrow reaches where the velocity leads in this time
MOTION_STEP_S = 0.2  # markers' positions are sampled this often; linear in between
GROUP_STEP_S = 0.2  # the groups layer draws a tracking cycle at most this often
TRAIL_S = 1.0  # how long a frame's detections stay on while the animation plays
CLOCK_STEP_S = 0.1
DIAMOND = 3.0  # half the diagonal of a detection's diamond, user units
LABEL_OFFSET = (4.5, 1.5)  # a detection's label's start from its centre along and across the baseline, user units
LABEL_STEP_M = 0.5
_MARGIN, _TOP, _BOTTOM = 100.0, 100.0, 100.0  # user units around the data, above it (title, clock), below (scale)


def _rows(a, cols: int, name: str) -> np.ndarray:
    """Rows as float [n, cols] (later columns dropped, as groundtruth.csv's beams and visibility); None is none."""
    if a is None:
        return np.zeros((0, cols))
    a = np.asarray(a, dtype=np.float64)
    if a.size == 0:
        return np.zeros((0, cols))
    if a.ndim != 2 or a.shape[1] < cols:
        raise ValueError(f"{name} must have shape [n, {cols}], got {a.shape}")
    return a[:, :cols]


def _uu(xy: np.ndarray) -> np.ndarray:
    """Metres to user units, y flipped up; + 0.0 turns -0.0 into 0.0."""
    return np.column_stack([xy[:, 0] * UNITS_PER_M, -xy[:, 1] * UNITS_PER_M]) + 0.0


def _pts(p: np.ndarray, sep: str = " ") -> str:
    """'x,y x,y ...' with 1 mm precision, by one % over a repeated template (a loop over numpy rows is 4x slower)."""
    return (("%.1f,%.1f" + sep) * len(p) % tuple(p.ravel()))[: -len(sep)]


def _colour(i: float) -> str:
    """A hue per id, 137.5 degrees (the golden angle) apart, so consecutive ids differ the most."""
    return f"hsl({int(i) * 137.508 % 360:.0f},75%,40%)"


def _by_id(rows: np.ndarray):
    """(id, rows sorted by time) per id of rows [t, id, x, y, ...]."""
    rows = rows[np.lexsort((rows[:, 0], rows[:, 1]))]
    return ((g[0, 1], g) for g in np.split(rows, np.flatnonzero(np.diff(rows[:, 1])) + 1) if len(g))


def _arrows(t: np.ndarray, xy: np.ndarray, v: np.ndarray) -> str:
    """Path data of one track's velocity arrows, at its first row and every ARROW_EVERY_S after; none at rest."""
    k = np.floor((t - t[0]) / ARROW_EVERY_S + 1e-9)
    speed = np.hypot(v[:, 0], v[:, 1])
    pick = np.r_[True, k[1:] != k[:-1]] & (speed > 0)  # NaN speed is not > 0
    p, v, speed = xy[pick], v[pick], speed[pick]
    tip = p + v * ARROW_LEAD_S
    back = -v / speed[:, None] * 0.15  # barbs 15 cm long, 25 degrees off the line
    c, s = np.cos(np.radians(25.0)), np.sin(np.radians(25.0))
    b1 = tip + np.column_stack([c * back[:, 0] - s * back[:, 1], s * back[:, 0] + c * back[:, 1]])
    b2 = tip + np.column_stack([c * back[:, 0] + s * back[:, 1], -s * back[:, 0] + c * back[:, 1]])
    q = np.hstack([_uu(p), _uu(tip), _uu(b1), _uu(tip), _uu(b2)])
    return "M%.1f,%.1fL%.1f,%.1fM%.1f,%.1fL%.1f,%.1f %.1f,%.1f" * len(q) % tuple(q.ravel())


def _show(begin: float, dur: float | None = None, freeze: bool = False) -> str:
    """Shows the parent, display:none until then, from ``begin`` for ``dur`` (or for good), held at the end."""
    d = "" if dur is None else f' dur="{dur:.3f}s"'
    f = ' fill="freeze"' if freeze else ""
    return f'<set attributeName="display" to="inline" begin="{begin:.3f}s"{d}{f}/>'


def _marker(t: np.ndarray, p: np.ndarray, t_lo: float, dt: float, body: str) -> str:
    """A marker that follows user-unit points p at times t from the first row to one frame (dt) after the last."""
    dur = t[-1] - t[0] + dt
    ts = np.linspace(t[0], t[0] + dur, int(np.ceil(dur / MOTION_STEP_S - 1e-9)) + 1)
    q = np.column_stack([np.interp(ts, t, p[:, 0]), np.interp(ts, t, p[:, 1])])
    b = t[0] - t_lo
    return (f'<g display="none">{_show(b, dur)}<animateMotion begin="{b:.3f}s" dur="{dur:.3f}s" calcMode="linear" '
            f'values="{_pts(q, ";")}"/>{body}</g>')


def _label_angles(p: np.ndarray, prev: np.ndarray) -> np.ndarray:
    """Degrees (SVG's, clockwise) of the labels' baselines at detections p [n, 2] (m): across the step from the
    nearest detection of the previous frame within LABEL_STEP_M, so that the labels of someone walking stack like
    the rungs of a ladder instead of overlapping (at 25 Hz a step is 5 cm, a label 12 cm long); horizontal where
    there is none; never upside down."""
    a = np.zeros(len(p))
    if len(p) and len(prev):
        d = cdist(p, prev)
        j = d.argmin(1)
        ok = d[np.arange(len(p)), j] <= LABEL_STEP_M
        m = p[ok] - prev[j[ok]]
        a[ok] = np.degrees(np.arctan2(m[:, 0], m[:, 1]))  # (m_y, m_x) is across (m_x, -m_y), the step on screen
    return (a + 90.0) % 180.0 - 90.0


def _detections(det: np.ndarray, t_lo: float, t_end: float, animate: bool) -> tuple[list[str], list[str]]:
    """Per frame of rows [t, id, x, y]: a group with one path of its diamonds, and one with an 'id time' text beside
    each; the labels go in a layer above all diamonds, else the next frames' diamonds cover them."""
    det = det[np.argsort(det[:, 0], kind="stable")]
    shapes, labels = [], []
    r = f"{DIAMOND:g}"
    diamond = f"M%.1f,%.1fl{r},{r}-{r},{r}-{r},-{r}z"  # from the top vertex clockwise (on screen)
    prev = np.zeros((0, 2))
    for f in np.split(det, np.flatnonzero(np.diff(det[:, 0])) + 1):
        if not len(f):
            continue
        p = _uu(f[:, 2:4])
        b = f[0, 0] - t_lo
        head = f'<g display="none">{_show(b, TRAIL_S)}{_show(t_end, freeze=True)}' if animate else "<g>"
        shapes.append(f'{head}<path d="{diamond * len(p) % tuple((p - [0.0, DIAMOND]).ravel())}"/></g>')
        a = _label_angles(f[:, 2:4], prev)
        c, s = np.cos(np.radians(a)), np.sin(np.radians(a))
        u, v = LABEL_OFFSET
        lab = np.column_stack([p[:, 0] + u * c - v * s, p[:, 1] + u * s + v * c, a, f[:, 1], f[:, 0]])
        labels.append(head + '<text transform="translate(%.0f %.0f)rotate(%.0f)">%d %.2f</text>' * len(f)
                      % tuple(lab.ravel()) + "</g>")
        prev = f[:, 2:4]
    return shapes, labels


def _members(grp: np.ndarray, trf: np.ndarray) -> np.ndarray:
    """Positions [n, 2] (m) of the members of group rows [frame, t, group, id, x, y]: the row of the same frame and
    track id in track rows [frame, t, id, x, y, ...]; NaN where there is none."""
    out = np.full((len(grp), 2), np.nan)
    trf = trf[np.isfinite(trf[:, 0])]
    if not len(grp) or not len(trf):
        return out
    keys = np.concatenate([trf[:, [0, 2]], grp[:, [0, 3]]])
    code = np.unique(keys, axis=0, return_inverse=True)[1].ravel()
    at = np.full((code.max() + 1, 2), np.nan)
    at[code[:len(trf)]] = trf[:, 3:5]
    return at[code[len(trf):]]


def _cycles(times: np.ndarray, animate: bool) -> np.ndarray:
    """The tracking cycles' times whose groups are drawn: back from the last, none closer than GROUP_STEP_S to the
    one after it; when not animated, the last alone."""
    if not len(times) or not animate:
        return times[-1:]
    picked = [times[-1]]
    for t in times[-2::-1].tolist():
        if t <= picked[-1] - GROUP_STEP_S + 1e-9:
            picked.append(t)
    return np.array(picked[::-1])


def _groups(grp: np.ndarray, member: np.ndarray, cycles: np.ndarray, t_lo: float, animate: bool) -> list[str]:
    """Per drawn cycle of group rows [frame, t, group, id, x, y] with their members' positions [n, 2]: a <g> with,
    per group, a path from each member found to the centroid and "G<id>" at the centroid; when animated shown from
    the cycle's time until the next drawn cycle's, the last one for good."""
    pick = np.isin(grp[:, 1], cycles)
    order = np.lexsort((grp[pick, 3], grp[pick, 2], grp[pick, 1]))
    grp, member = grp[pick][order], member[pick][order]
    out = []
    for f in np.split(np.arange(len(grp)), np.flatnonzero(np.diff(grp[:, 1])) + 1):
        if not len(f):
            continue
        t = grp[f[0], 1]
        if animate:
            k = int(np.searchsorted(cycles, t))
            dur = cycles[k + 1] - t if k + 1 < len(cycles) else None
            head = f'<g display="none">{_show(t - t_lo, dur, freeze=dur is None)}'
        else:
            head = "<g>"
        body = []
        for g in np.split(f, np.flatnonzero(np.diff(grp[f, 2])) + 1):
            i, c = grp[g[0], 2], _colour(grp[g[0], 2])
            hub = _uu(grp[g[:1], 4:6])[0]
            m = _uu(member[g])
            m = m[np.isfinite(m).all(1)]
            if len(m):
                q = np.column_stack([m, np.broadcast_to(hub, m.shape)])
                body.append(f'<path stroke="{c}" d="{"M%.1f,%.1fL%.1f,%.1f" * len(q) % tuple(q.ravel())}"/>')
            body.append(f'<text x="{hub[0]:.1f}" y="{hub[1]:.1f}" fill="{c}">G{i:.0f}</text>')
        out.append(head + "".join(body) + "</g>")
    return out


def _clock(t_lo: float, t_end: float) -> list[str]:
    """One text per CLOCK_STEP_S, each shown for its step; the last one stays."""
    n = int(np.floor(t_end / CLOCK_STEP_S + 1e-9)) + 1
    return [f'<text display="none">{t_lo + k * CLOCK_STEP_S:.1f} s'
            f'{_show(k * CLOCK_STEP_S, CLOCK_STEP_S, freeze=k == n - 1)}</text>' for k in range(n)]


def _nice(x: float) -> float:
    """The largest 1, 2 or 5 times a power of ten not above x: a round scale-bar length."""
    e = 10.0 ** np.floor(np.log10(x))
    return max(m * e for m in (1, 2, 5) if m * e <= x)


def write_svg(path, *, tracks: np.ndarray, detections: np.ndarray | None = None,
              groundtruth: np.ndarray | None = None, robot: np.ndarray | None = None,
              walls: np.ndarray | None = None, groups: np.ndarray | None = None, start: float | None = None,
              end: float | None = None, animate: bool = True, title: str = "") -> None:
    """Write the top-down view of a run to ``path``; all positions in one frame of reference, metres.

    ``tracks`` and ``groundtruth``: rows (frame, t, id, x, y, vx, vy); ``detections``: (frame, t, id, x, y);
    ``robot``: odometry rows (t, x, y); ``walls``: segments [k, 2, 2]; ``groups``: rows (frame, t, group, id, x,
    y[, age]) as groups.csv holds them, one per member track ``id`` of each group, (x, y) the group's centroid; the
    members are drawn where the tracks' rows of the same frame and id put them. Only rows with ``start <= t <= end``
    (seconds; by default the first and last time of any row) are drawn, and the animation's time 0 is ``start``.
    Rows with a non-finite time or position are left out.
    """
    trf = _rows(tracks, 7, "tracks")  # with the frame, to find the groups' members
    grp = _rows(groups, 6, "groups")  # frame, t, group, id, x, y
    gt = _rows(groundtruth, 7, "groundtruth")[:, 1:]
    det = _rows(detections, 5, "detections")[:, 1:]
    rb = _rows(robot, 3, "robot")
    rb = np.column_stack([rb[:, 0], np.zeros(len(rb)), rb[:, 1:]])
    walls = np.zeros((0, 2, 2)) if walls is None else np.asarray(walls, dtype=np.float64).reshape(-1, 2, 2)
    every = np.concatenate([a[:, 0] for a in (trf[:, 1:], gt, det, rb, grp[:, 1:])])
    t_lo = float(start) if start is not None else float(every.min()) if every.size else 0.0
    t_hi = float(end) if end is not None else float(every.max()) if every.size else t_lo
    if t_hi < t_lo:
        raise ValueError(f"end ({t_hi}) is before start ({t_lo})")

    def window(a):
        return a[(a[:, 0] >= t_lo) & (a[:, 0] <= t_hi) & np.isfinite(a[:, :4]).all(1)]

    trf = trf[(trf[:, 1] >= t_lo) & (trf[:, 1] <= t_hi) & np.isfinite(trf[:, 1:5]).all(1)]
    grp = grp[(grp[:, 1] >= t_lo) & (grp[:, 1] <= t_hi) & np.isfinite(grp).all(1)]
    tr, gt, det, rb = trf[:, 1:], window(gt), window(det), window(rb)
    rb = rb[np.argsort(rb[:, 0], kind="stable")]
    tracks_by_id, gt_by_id = list(_by_id(tr)), list(_by_id(gt))
    t_end = t_hi - t_lo
    times = np.unique(np.concatenate([tr[:, 0], gt[:, 0], det[:, 0]]))
    dt = float(np.median(np.diff(times))) if times.size > 1 else CLOCK_STEP_S  # one frame

    xy = np.concatenate([a[:, 2:4] for a in (tr, gt, det, rb)] + [grp[:, 4:6], walls.reshape(-1, 2)])
    xy = xy[np.isfinite(xy).all(1)]
    lo, hi = (xy.min(0), xy.max(0)) if len(xy) else (np.zeros(2), np.zeros(2))
    x0, y0 = lo[0] * UNITS_PER_M - _MARGIN, -hi[1] * UNITS_PER_M - _MARGIN - _TOP
    w = (hi[0] - lo[0]) * UNITS_PER_M + 2 * _MARGIN
    h = (hi[1] - lo[1]) * UNITS_PER_M + 2 * _MARGIN + _TOP + _BOTTOM

    # what does not move gets a layer of its own in Chrome, painted once: else each marker's step repaints it all
    layer = ' style="will-change:transform"' if animate else ""
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="{x0:.1f} {y0:.1f} {w:.1f} {h:.1f}" '
           f'width="{w * PX_PER_UNIT:.0f}" height="{h * PX_PER_UNIT:.0f}" font-family="sans-serif">',
           f'<rect x="{x0:.1f}" y="{y0:.1f}" width="{w:.1f}" height="{h:.1f}" fill="white"/>',
           f'<g id="map"{layer}><g id="walls" stroke="#333" stroke-width="8" stroke-linecap="round">']
    for a, b in _uu(walls.reshape(-1, 2)).reshape(-1, 2, 2):
        out.append(f'<line x1="{a[0]:.1f}" y1="{a[1]:.1f}" x2="{b[0]:.1f}" y2="{b[1]:.1f}"/>')
    out.append('</g><g id="robot" fill="none" stroke="#bbb" stroke-width="12" stroke-linejoin="round">')
    if len(rb):
        out.append(f'<polyline points="{_pts(_uu(rb[:, 2:4]))}"/>')
    out.append('</g><g id="groundtruth" fill="none" stroke="#999" stroke-width="2">')
    out += [f'<polyline points="{_pts(_uu(g[:, 2:4]))}"/>' for _, g in gt_by_id]
    out.append('</g><g id="tracks" fill="none" stroke-width="4" stroke-linejoin="round" font-size="25">')
    for i, g in tracks_by_id:
        c, p = _colour(i), _uu(g[:, 2:4])
        out.append(f'<g stroke="{c}"><polyline points="{_pts(p)}"/><path d="{_arrows(g[:, 0], g[:, 2:4], g[:, 4:6])}"/>'
                   f'<text x="{p[0, 0] + 10:.0f}" y="{p[0, 1] - 10:.0f}" fill="{c}" stroke="none">{i:.0f}</text>'
                   f'<text x="{p[-1, 0] + 10:.0f}" y="{p[-1, 1] - 10:.0f}" fill="{c}" stroke="none">{i:.0f}</text></g>')
    cycles = _cycles(np.unique(np.concatenate([tr[:, 0], grp[:, 1]])), animate)
    out += ['</g></g><g id="groups" fill="none" stroke-width="3" font-size="25" font-weight="bold" '
            'text-anchor="middle">', *_groups(grp, _members(grp, trf), cycles, t_lo, animate)]
    shapes, labels = _detections(det, t_lo, t_end, animate)
    # a white outline keeps overlapping diamonds apart; none on the labels: Firefox plays 7 frames/s with it, 32 without
    out += ['</g><g id="detections" fill="#222" stroke="white" stroke-width="0.6">', *shapes,
            '</g><g id="detection-labels" fill="#222" font-size="4">', *labels]
    out.append("</g>")
    if animate:
        out.append('<g id="markers" font-size="30" font-weight="bold">')
        out += [_marker(g[:, 0], _uu(g[:, 2:4]), t_lo, dt, '<circle r="10" fill="#999"/>') for _, g in gt_by_id]
        if len(rb):
            out.append(_marker(rb[:, 0], _uu(rb[:, 2:4]), t_lo, dt, '<circle r="30" fill="#888"/>'))
        out += [_marker(g[:, 0], _uu(g[:, 2:4]), t_lo, dt,
                        f'<g fill="{_colour(i)}"><circle r="15"/><text x="18" y="-18">{i:.0f}</text></g>')
                for i, g in tracks_by_id]
        out.append(f'</g><g id="clock" font-size="50" text-anchor="end" transform="translate({x0 + w - 50:.1f} '
                   f'{y0 + 75:.1f})">')
        out += _clock(t_lo, t_end)
        out.append("</g>")
    else:
        out.append(f'<text id="clock" x="{x0 + w - 50:.1f}" y="{y0 + 75:.1f}" font-size="50" text-anchor="end">'
                   f'{t_lo:.1f} to {t_hi:.1f} s</text>')
    bar = _nice(w / UNITS_PER_M / 4)
    bx, by = x0 + 50, y0 + h - 50
    out.append(f'<g id="scale"><path d="M{bx:.1f},{by - 15:.1f}V{by:.1f}H{bx + bar * UNITS_PER_M:.1f}V{by - 15:.1f}" '
               f'fill="none" stroke="black" stroke-width="5"/><text x="{bx + bar * UNITS_PER_M / 2:.1f}" '
               f'y="{by - 15:.1f}" font-size="30" text-anchor="middle">{bar:g} m</text></g>')
    out.append(f'<text id="title" x="{x0 + 50:.1f}" y="{y0 + 75:.1f}" font-size="50">{escape(title)}</text></svg>\n')
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("".join(out))

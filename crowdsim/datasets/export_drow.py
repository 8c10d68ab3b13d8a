"""DROW v2 export: one laser's scans and person labels in the layout DROW's and DR-SPAAM's loaders read unchanged.

Layout (DROW ``README.md``, "Detailed format description"; DR-SPAAM ``dr_spaam/dr_spaam/datahandle/drow_handle.py``
``DROWHandle``, which globs ``data_dir/<split>/*.csv``, and ``dataset/builder.py``, which picks the DROW loader when
``data_dir`` contains "DROW"): ``OUT/DROWv2-data/{train,val,test}/<episode>.{csv,wp,wa,wc,odom2}``.

* ``.csv``: one line per scan, ``seq,t,r_0,...,r_449``: seq is the scan's frame index in the episode (unique and
  ascending, as the loaders need), t the simulation time in s, the ranges in m on DROW's beam grid: 450 beams 0.5
  degrees apart from -112.25 degrees (DROW ``v2/utils/__init__.py`` ``laser_angles``; ``drow_handle.py``
  ``get_laser_phi``), the grid of ``preset: sick_s300``. No return (our NaN) and anything beyond it is written as
  DROW's magic value 29.96 ("a 'magic value' for that distance at 29.96 which means N/A", DROW README).
* ``.wp`` / ``.wa`` / ``.wc`` (persons, walking aids, wheelchairs): ``seq,[[r, phi], ...]`` (JSON) for every scan,
  the same seqs in all three; r in m from the laser, phi in rad in the laser's frame (x forward, y left, positive
  to the left as the DROW README has it), the same angle the beam grid gives each range. Labelled are the persons
  the scan sees, as DROW's annotators labelled what the scan shows: at least ``MIN_BEAMS`` beams hit them (the
  scan's own per-beam person ids), at their true centre at the scan's time. Our crowd has persons only: an agent
  type named ``wheelchair`` or ``walking_aid`` would go to ``.wc`` / ``.wa``, every other type to ``.wp``.
* ``.odom2`` (DROW v2's odometry, read by DROW's notebooks, not by DR-SPAAM): ``seq,t,x,y,phi`` per scan, the
  laser's pose in odom.

DROW's README says the first csv value is the leftmost beam; its angle convention, its code and DR-SPAAM's ROS node
(index 0 at ROS's angle_min) put index 0 at the right. We follow the code: beam i at angle_min + i * increment,
counter-clockwise, as in the laser's LaserScan.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from pipeline.frames import compose

from .layout import DatasetError
from .reader import to_sensor

BEAMS = 450
INCREMENT = np.radians(0.5)
ANGLE_MIN = -(BEAMS - 1) * INCREMENT / 2
NO_RETURN = 29.96  # DROW's "N/A" range
MIN_BEAMS = 1  # beams on a person for a label
FOLDER = "DROWv2-data"  # DR-SPAAM picks its DROW loader by this name in data_dir
LABEL_FILE = {"wheelchair": "wc", "walking_aid": "wa"}  # agent type -> label file; any other type: "wp"
BLOCK = 256  # scans read and written at once


def _fits(cal: dict) -> bool:
    return (cal["n_beams"] == BEAMS and abs(cal["angle_increment"] - INCREMENT) < 1e-9
            and abs(cal["angle_min"] - ANGLE_MIN) < 1e-9)


def check(episodes, laser: str | None) -> list[str]:
    """Each episode's laser on DROW's beam grid: ``laser`` if given, else the first that fits; DatasetError naming
    the episode when there is none."""
    out = []
    for ep, _ in episodes:
        lasers = ep.meta["calibration"]["lasers"]
        if laser is not None and laser not in lasers:
            raise DatasetError(f"--laser {laser}: {ep.folder} has no such laser; expected one of {', '.join(lasers)}")
        fits = [name for name in ([laser] if laser else lasers) if _fits(lasers[name])]
        if not fits:
            raise DatasetError(f"{ep.folder}: {f'laser {laser}' if laser else 'no laser'} on DROW's beam grid; "
                               f"expected 450 beams 0.5 degrees apart from -112.25 degrees (a laser with preset: "
                               "sick_s300)")
        if ep.sensor(fits[0])["stamp"].shape[0] < 2:
            raise DatasetError(f"{ep.folder}: laser {fits[0]} has fewer than 2 scans; DROW's loaders need 2 or more")
        out.append(fits[0])
    return out


def write(episodes, lasers: list[str], out: Path) -> dict:
    """Every episode as a DROW sequence under ``out/DROWv2-data/<split>/``; the counts of scans and labels."""
    scans = labels = 0
    for (ep, split), laser in zip(episodes, lasers):
        folder = out / FOLDER / split
        folder.mkdir(parents=True, exist_ok=True)
        n, k = _write_sequence(ep, laser, folder / ep.folder.name)
        scans, labels = scans + n, labels + k
    return {"laser": sorted(set(lasers)), "scans": scans, "labels": labels}


def _write_sequence(ep, laser: str, stem: Path) -> tuple[int, int]:
    cal = ep.meta["calibration"]["lasers"][laser]
    mount = (cal["x"], cal["y"], cal["yaw"])
    group, robot = ep.sensor(laser), ep.h5["robot"]
    persons = ep.iter_frames("persons", ["id", "agent_type", "x", "y"])
    files = {ext: open(f"{stem}.{ext}", "w") for ext in ("csv", "wp", "wa", "wc", "odom2")}
    count = labels = 0
    try:
        for a in range(0, group["stamp"].shape[0], BLOCK):
            frames, stamps = group["frame"][a:a + BLOCK], group["stamp"][a:a + BLOCK]
            ranges = group["ranges"][a:a + BLOCK].astype(np.float64)
            ranges[~(ranges <= NO_RETURN)] = NO_RETURN  # NaN (no return) and beyond
            span = slice(int(frames[0]), int(frames[-1]) + 1)  # the robot's rows of these frames
            pose = robot["pose"][span][frames - frames[0]]
            odom = robot["odom"][span][frames - frames[0]]
            np.savetxt(files["csv"], np.column_stack([frames, stamps, ranges]), delimiter=",",
                       fmt=["%d", "%.6f"] + ["%.3f"] * BEAMS)
            sensor = compose(odom, np.array(mount))  # the laser's pose in odom
            np.savetxt(files["odom2"], np.column_stack([frames, stamps, sensor]), delimiter=",",
                       fmt=["%d", "%.6f", "%.4f", "%.4f", "%.5f"])
            person_id = group["person_id"][a:a + BLOCK]
            for k, frame in enumerate(frames):
                persons_of = _advance(persons, int(frame))
                ids, beams = np.unique(person_id[k][person_id[k] >= 0], return_counts=True)
                seen = np.isin(persons_of["id"], ids[beams >= MIN_BEAMS])
                xy = to_sensor(np.column_stack([persons_of["x"], persons_of["y"]])[seen], pose[k], mount)
                kind = np.array([LABEL_FILE.get(t, "wp") for t in persons_of["agent_type"][seen]], dtype=object)
                for ext in ("wp", "wa", "wc"):
                    pick = xy[kind == ext]
                    polar = [[round(float(r), 4), round(float(p), 5)]
                             for r, p in zip(np.hypot(pick[:, 0], pick[:, 1]), np.arctan2(pick[:, 1], pick[:, 0]))]
                    files[ext].write(f"{int(frame)},{json.dumps(polar)}\n")
                labels += int(seen.sum())
            count += len(frames)
    finally:
        for f in files.values():
            f.close()
    return count, labels


def _advance(persons, frame: int) -> dict:
    """The persons rows of ``frame`` from the frame-ordered iterator (frames before it are skipped)."""
    for f, rows in persons:
        if f == frame:
            return rows
    raise DatasetError(f"persons.parquet: no frame {frame}; expected every frame of the episode")


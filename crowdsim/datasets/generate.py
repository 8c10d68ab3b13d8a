"""``crowdsim dataset generate``: N episodes of one or more scenarios, in parallel and resumably.

Episode k runs scenario k mod S (of the S named) at the seed drawn from the k-th child of ``SeedSequence(root)``;
its variations (crowd rate and density, the robot's route) come from that child too, so an episode's bytes depend on
the command and k alone, never on the workers, the engine or the order of completion.

Each episode is written into a hidden temporary folder in the dataset and renamed into place when complete; the
manifest, rewritten atomically after each, lists only complete episodes with every file's size and sha256. Running
the command again verifies those checksums and redoes only what is missing or corrupt: a ``kill -9`` anywhere loses
at most the episodes in flight. A folder that holds anything else, or a dataset of a different command, is refused.

Everything is checked before the first simulation: the options, that every episode holds a frame, and the folder
(an existing folder, or one that can be made, in which a file can be written). Whatever stops the command later (an
error in an episode, a full disk, Ctrl-C, SIGTERM as the CLI turns it into KeyboardInterrupt), the workers are
stopped, the episodes in progress removed and the complete ones kept with a manifest listing exactly them: the
folder is what ``kill -9`` would have left, tidied, and with no complete episode it is as it was before.
"""

from __future__ import annotations

import errno
import json
import os
import re
import shutil
from concurrent.futures import FIRST_COMPLETED, wait
from multiprocessing import get_context
from pathlib import Path

import numpy as np
from tqdm import tqdm

from scenarios.geometry import closest_on_segments, segments_cross
from scenarios.typed import Scenario, as_written

from .. import __version__
from ..outdir import RunDirError, check_out_dir
from ..stops import stops_held
from ..workers import process_pool, ray_results, ray_session
from .episode import COMPRESSIONS, write_episode
from .layout import (EPISODE_FILES, DatasetError, FORMAT_VERSION, MANIFEST, SPLITS, episode_id, episode_seeds, file_digest,
                     in_mini, scenario_digest, split_of)

TMP_PREFIX = ".tmp-"
ROUTE_CLEARANCE = 0.3  # m beyond the robot's radius a jittered waypoint keeps from every wall, or it stays put
DISK_FULL = (errno.ENOSPC, errno.EDQUOT, errno.EFBIG)  # a write refused for space: disk, quota, file size limit


def vary(scenario: Scenario, rng: np.random.Generator, rate: tuple[float, float] | None,
         density: tuple[float, float] | None, route_jitter: float) -> tuple[Scenario, dict]:
    """The episode's scenario and what was drawn: every source's rate times one factor uniform in ``rate``; every
    agent cluster's and standing group's count times one factor uniform in ``density`` (rounded, at least 1); the
    robot's start and route waypoints (its start alone for a robot without ``robot.route``: one driven to goals,
    following a person or scripted) each moved uniformly within a disc of ``route_jitter`` m, a point kept where it
    was where the move would cross a wall or come within the robot's radius plus ROUTE_CLEARANCE of one. The draws
    are made in that order, each only when asked for, so adding one option leaves the others' draws as they were;
    ``route_offsets`` lists the start's offset first, then each waypoint's."""
    sc, drawn = scenario, {}
    if rate is not None:
        f = float(rng.uniform(*rate))
        sc = sc.replace(sources=[source.replace(rate=source.rate * f) for source in sc.sources])
        drawn["rate_scale"] = f
    if density is not None:
        f = float(rng.uniform(*density))
        # the standing groups alone, as before: the old loop also read an "agents" key, which the format has not,
        # so ``clusters`` keep their counts (the docstring's "agent cluster" never was scaled)
        sc = sc.replace(standing=[group.replace(count=max(1, int(round(group.count * f)))) for group in sc.standing])
        drawn["density_scale"] = f
    if route_jitter > 0:
        robot = sc.robot
        route = robot.route  # None for a robot driven otherwise (goals, follow, script): its start alone
        points = np.array([robot.start[:2], *(route or [])], float).reshape(-1, 2)
        r = route_jitter * np.sqrt(rng.uniform(size=len(points)))
        a = rng.uniform(0, 2 * np.pi, len(points))
        moved = points + np.column_stack([r * np.cos(a), r * np.sin(a)])
        walls = sc.map.segments
        if len(walls):
            clear = closest_on_segments(moved, walls)[1].min(axis=1) > robot.radius + ROUTE_CLEARANCE
            clear &= ~segments_cross(points, moved, walls)  # never through a wall (out of the map, into a pillar)
            moved = np.where(clear[:, None], moved, points)
        start = [float(moved[0, 0]), float(moved[0, 1]), robot.start[2]]
        sc = sc.replace(robot=robot.replace(start=start) if route is None
                        else robot.replace(start=start, route=moved[1:].tolist()))
        drawn["route_offsets"] = (moved - points).tolist()
    return sc, drawn


def plan(scenarios: list[Scenario], episodes: int, seed: int, duration: float | None, rate, density,
         route_jitter: float) -> list[dict]:
    """Every episode's id, split, scenario (varied), seed and duration: a pure function of the arguments."""
    out = []
    for k in range(episodes):
        base = scenarios[k % len(scenarios)]
        sim_seed, rng = episode_seeds(seed, k)
        scenario, drawn = vary(base, rng, rate, density, route_jitter)
        scenario = scenario.replace(seed=sim_seed)
        out.append({"id": episode_id(k), "index": k, "split": split_of(k), "mini": in_mini(k),
                    "scenario": scenario.name, "scenario_sha256": scenario_digest(base), "seed": sim_seed,
                    "variation": drawn, "duration": float(duration if duration is not None else base.duration),
                    "spec": scenario})
    return out


def command_line(names: list[str], episodes: int, seed: int, duration: float | None, rate, density,
                 route_jitter: float, compression: str) -> str:
    """The command as the manifest records it: what decides the bytes (not the workers, the engine or DIR)."""
    parts = ["crowdsim dataset generate", *names, f"--episodes {episodes}", f"--seed {seed}"]
    if duration is not None:
        parts.append(f"--duration {duration:g}")
    if rate is not None:
        parts.append(f"--rate-scale {rate[0]:g} {rate[1]:g}")
    if density is not None:
        parts.append(f"--density-scale {density[0]:g} {density[1]:g}")
    if route_jitter > 0:
        parts.append(f"--route-jitter {route_jitter:g}")
    if compression != "gzip":
        parts.append(f"--compression {compression}")
    return " ".join(parts)


def _episode_files(folder: Path) -> dict:
    return {name: dict(zip(("size", "sha256"), file_digest(folder / name))) for name in EPISODE_FILES}


class DiskFullError(DatasetError):
    """An episode that could not be written for want of space: a full disk, a quota, a file size limit. Raised where
    the episode is written (a worker, perhaps) and turned by ``generate`` into one error saying what was kept."""

    def __init__(self, episode: str, reason: str):
        super().__init__(episode, reason)  # the args pickle it back from a worker
        self.episode, self.reason = episode, reason

    def __str__(self) -> str:
        return f"{self.reason} while writing {self.episode}"


def _disk_full(e: BaseException) -> str | None:
    """The reason (``No space left on device``, ...) when ``e`` or an error it came from is a write refused for
    space; None otherwise. HDF5 reports it as a RuntimeError with the errno in its message."""
    seen = set()
    while e is not None and id(e) not in seen:
        seen.add(id(e))
        code = e.errno if isinstance(e, OSError) else None
        if code is None and isinstance(e, (OSError, RuntimeError)):
            found = re.search(r"errno = (\d+)", str(e))
            code = int(found.group(1)) if found else None
        if code in DISK_FULL:
            return os.strerror(code)
        e = e.__cause__ or e.__context__
    return None


def make_episode(job: dict, root: Path, compression: str, progress=None) -> dict:
    """Write one episode into a temporary folder under ``root`` and rename it into place; its manifest entry. On
    any error or interruption the temporary folder goes; a write refused for space is a DiskFullError."""
    final = root / job["id"]
    tmp = root / f"{TMP_PREFIX}{job['id']}-{os.getpid()}"
    try:
        shutil.rmtree(tmp, ignore_errors=True)
        tmp.mkdir()
        frames = write_episode(job["spec"], job["seed"], job["duration"], tmp, compression, progress)
        files = _episode_files(tmp)
        shutil.rmtree(final, ignore_errors=True)  # a corrupt copy found by the check
        tmp.rename(final)
    except BaseException as e:
        shutil.rmtree(tmp, ignore_errors=True)
        reason = _disk_full(e) if isinstance(e, Exception) else None
        if reason is not None:
            raise DiskFullError(job["id"], reason) from None
        raise
    entry = {k: job[k] for k in ("id", "split", "mini", "scenario", "scenario_sha256", "seed", "variation",
                                 "duration")}
    return {**entry, "frames": frames, "status": "complete", "files": files}


_worker: dict = {}


def _start_worker(counter) -> None:
    """A pool worker (deaf to stops, crowdsim/workers.py: the main process decides what to keep, ends the workers
    and tidies the folder): the shared frame counter."""
    _worker["counter"] = counter


def _tick(stamp: float) -> None:
    with _worker["counter"].get_lock():
        _worker["counter"].value += 1


def _run_local(job: dict, root: str, compression: str) -> dict:
    return make_episode(job, Path(root), compression, _tick)


def _write_manifest(root: Path, header: dict, done: dict[str, dict]) -> None:
    manifest = {**header, "episodes": [done[k] for k in sorted(done)],
                "splits": {s: [k for k in sorted(done) if done[k]["split"] == s] for s in SPLITS},
                "mini": [k for k in sorted(done) if done[k]["mini"]]}
    tmp = root / f"{TMP_PREFIX}{MANIFEST}"
    try:
        tmp.write_text(json.dumps(manifest, indent=1) + "\n")
        os.replace(tmp, root / MANIFEST)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def _verified(root: Path, entry: dict) -> bool:
    folder = root / entry["id"]
    try:
        return all(file_digest(folder / name) == (f["size"], f["sha256"]) for name, f in entry["files"].items())
    except OSError:
        return False


def _check_folder(root: Path, command: str) -> dict[str, dict]:
    """The complete, verified episodes of a dataset of ``command`` already in ``root`` (none if it is new or
    empty); DatasetError for a folder that holds anything else. Leftover temporary folders go; so does an episode
    folder the manifest does not list (its rename happened, the manifest's update did not)."""
    if not root.exists():
        return {}
    if not root.is_dir():
        raise DatasetError(f"--out {root}: not a directory; expected a new or empty folder, or a dataset of this "
                           "command to complete")
    entries = list(root.iterdir())
    if not entries:
        return {}
    manifest_path = root / MANIFEST
    if not manifest_path.exists():
        raise DatasetError(f"--out {root}: not empty and holds no {MANIFEST}; expected a new or empty folder, or a "
                           "dataset of this command to complete (nothing was written)")
    try:
        manifest = json.loads(manifest_path.read_text())
        previous = manifest["command"]
    except (ValueError, KeyError, TypeError):
        raise DatasetError(f"{manifest_path}: not a crowdsim dataset manifest (nothing was written)") from None
    if previous != command:
        raise DatasetError(f"--out {root}: a dataset of another command ({previous}); expected a new or empty "
                           f"folder, or the same command to complete it (nothing was written)")
    known = {e["id"] for e in manifest["episodes"]}
    allowed = known | {MANIFEST}
    for path in entries:
        if path.name.startswith(TMP_PREFIX) or (path.is_dir() and path.name.startswith("episode_")
                                                and path.name not in known):
            shutil.rmtree(path) if path.is_dir() else path.unlink()
        elif path.name not in allowed:
            raise DatasetError(f"--out {root}: holds {path.name}, which is no part of the dataset; expected only "
                               f"its episodes and {MANIFEST} (nothing was written)")
    return {e["id"]: e for e in manifest["episodes"] if _verified(root, e)}


def _out_path(out) -> Path:
    """--out as a path; DatasetError for a name no folder can have (empty, a NUL character)."""
    text = os.fspath(out)
    if text == "":
        raise DatasetError("--out: expected a folder to write the dataset to, got an empty name")
    if "\0" in text:
        raise DatasetError(f"--out {text!r}: holds a NUL character; expected a legal folder name")
    return Path(text)


def _exists(path: Path, out: Path) -> bool:
    try:
        os.stat(path)
    except (FileNotFoundError, NotADirectoryError):
        return False
    except OSError as e:  # a name too long, a loop of links, no permission to look
        raise DatasetError(f"--out {out}: {e.strerror or e}; expected a folder to write the dataset to (nothing was "
                           "written)") from None
    return True


def _file_above(out: Path) -> Path | None:
    """The first folder above ``out`` that is in fact a file, if any."""
    for parent in reversed(out.absolute().parents):
        if parent.exists() and not parent.is_dir():
            return parent
    return None


def _remove_made(made: list[Path]) -> None:
    """Remove the folders this command made (innermost first) as far as they are empty."""
    for path in reversed(made):
        try:
            path.rmdir()
        except OSError:
            continue


def _open_folder(out: Path) -> list[Path]:
    """--out checked before any work: an existing folder, or a new one made now with its missing parents (returned,
    outermost first, for the caller to remove if nothing comes of it). DatasetError naming --out for a file, a name
    that cannot be made (a parent that is a file, a read-only or virtual file system, a name too long)."""
    if _exists(out, out):
        if not out.is_dir():
            raise DatasetError(f"--out {out}: not a directory; expected a new or empty folder, or a dataset of this "
                               "command to complete")
        return []
    try:
        check_out_dir(out)  # crowdsim/outdir.py's rules for a new output folder
    except RunDirError as e:
        raise DatasetError(str(e)) from None
    made = [p for p in (*reversed(out.absolute().parents), out.absolute()) if not _exists(p, out)]
    try:
        out.mkdir(parents=True)
    except OSError as e:
        _remove_made(made)
        file = _file_above(out) if e.errno in (errno.ENOTDIR, errno.EEXIST) else None
        why = f"{file} is a file, not a folder" if file is not None else e.strerror or str(e)
        raise DatasetError(f"--out {out}: cannot be made ({why}); expected a folder that can be created (nothing "
                           "was written)") from None
    return made


def _probe(out: Path) -> None:
    """DatasetError unless a file can be written in ``out`` (a read-only mount, a folder of someone else's)."""
    probe = out / f"{TMP_PREFIX}probe-{os.getpid()}"
    try:
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as e:
        raise DatasetError(f"--out {out}: cannot write in it ({e.strerror or e}); expected a folder you can write "
                           "to (nothing was written)") from None


def _check_frames(jobs: list[dict], duration: float | None) -> None:
    """DatasetError for an episode that would hold no frame: a duration under half the scenario's tick."""
    for job in jobs:
        dt = job["spec"].dt
        if int(round(job["duration"] / dt)) < 1:
            what = (f"--duration {duration:g}" if duration is not None
                    else f"{job['scenario']}: duration {job['duration']:g}")
            raise DatasetError(f"{what}: shorter than half of {job['scenario']}'s tick (dt {dt:g} s), so an episode "
                               f"would hold no frame; expected at least {dt:g} s (nothing was written)")


def _check_variations(planned: list[dict], allow_large: bool, rate, density, route_jitter: float) -> None:
    """Each episode's scenario as the variations made it, validated as its file was (``allow_large`` as the command
    loaded it): a factor can take a file that passed past a limit (people at once, a rate), which is refused now,
    naming the options, the episode and the key, rather than found in a worker or not at all."""
    options = [f"{o} {pair[0]:g} {pair[1]:g}" for o, pair in (("--rate-scale", rate), ("--density-scale", density))
               if pair is not None] + ([f"--route-jitter {route_jitter:g}"] if route_jitter > 0 else [])
    if not options:
        return
    from scenarios import ScenarioError, scenario_from_dict

    for job in planned:
        raw = {k: v for k, v in as_written(job["spec"]).items() if k != "source"}
        try:
            scenario_from_dict(raw, f"{job['scenario']} as {job['id']} varies it", allow_large)
        except ScenarioError as e:
            raise DatasetError(f"{', '.join(options)}: {e} (nothing was written)") from None


def _listed(root: Path) -> list[str]:
    try:
        return [e["id"] for e in json.loads((root / MANIFEST).read_text())["episodes"]]
    except (OSError, ValueError, KeyError, TypeError):
        return []


def _tidy(out: Path, header: dict, done: dict[str, dict], made: list[Path], had_manifest: bool) -> list[str]:
    """After an error or an interruption, with every worker stopped: the folder as ``kill -9`` would have left it,
    tidied. Temporary folders and files go, the manifest lists exactly the complete episodes, an episode folder it
    does not list goes; with no complete episode, the folder is as it was before (a folder this command made is
    removed, with the parents it made). Returns the ids kept."""
    try:
        entries = list(out.iterdir())
    except OSError:
        entries = []
    for path in entries:
        if path.name.startswith(TMP_PREFIX):
            shutil.rmtree(path, ignore_errors=True) if path.is_dir() else path.unlink(missing_ok=True)
    kept = sorted(done)
    if kept or had_manifest:
        try:
            _write_manifest(out, header, done)
        except OSError:  # the disk still full: the manifest as it is on disk says what is kept
            kept = _listed(out)
    for path in entries:
        if path.name.startswith("episode_") and path.name not in kept and path.is_dir():
            shutil.rmtree(path, ignore_errors=True)
    if not kept and not had_manifest:
        (out / MANIFEST).unlink(missing_ok=True)
        _remove_made(made)
    return kept


def _kept(out: Path, kept: list[str], episodes: int, made: list[Path]) -> str:
    """What a stopped command kept, in words for the one line the CLI prints."""
    if not kept:
        return "no episode was complete, so nothing was kept" + (f" ({out} is as it was)" if not made else "")
    return (f"kept {len(kept)} of {episodes} episodes in {out}, each complete and listed in {MANIFEST}; the same "
            "command completes the dataset")


def _space(reason: str) -> str:
    """A write refused for space, in words: the file size limit named as such."""
    return f"{reason} (over the file size limit, ulimit -f)" if reason == os.strerror(errno.EFBIG) else reason


def generate(scenarios: list[Scenario], names: list[str], out: Path, episodes: int, seed: int = 0,
             duration: float | None = None, workers: int = 1, ray_address: str | None = None,
             rate=None, density=None, route_jitter: float = 0.0, compression: str = "gzip",
             progress: bool = True, allow_large: bool = False) -> dict:
    """Generate (or complete) the dataset in ``out``; return its manifest.

    Every argument, every episode's scenario as varied (validated as its file was, past the cost limits only with
    ``allow_large``) and the folder are checked before any simulation (DatasetError, nothing written). Whatever
    stops the generation (an error, a full disk, KeyboardInterrupt: Ctrl-C, or SIGTERM as the CLI turns it into
    one), the workers are stopped, the episodes in progress removed, and the complete ones kept with a manifest
    listing exactly them, as after ``kill -9`` and ready for the same command to complete; with none complete the
    folder is left as it was. A full disk is one DatasetError saying what was kept; any other exception goes on
    as it was, with ``kept`` (a sentence: what was kept, where) set on it for the CLI's one line."""
    if episodes < 1:
        raise DatasetError(f"--episodes: expected at least 1, got {episodes}")
    if workers < 1:
        raise DatasetError(f"--workers: expected at least 1 process, got {workers}")
    if seed < 0:
        raise DatasetError(f"--seed: expected a seed of at least 0, got {seed}")
    if duration is not None and not (np.isfinite(duration) and duration > 0):
        raise DatasetError(f"--duration: expected a time above 0 s, got {duration}")
    for option, pair in (("--rate-scale", rate), ("--density-scale", density)):
        if pair is not None and not (0 <= pair[0] <= pair[1] and np.isfinite(pair[1])):
            raise DatasetError(f"{option}: expected LO HI with 0 <= LO <= HI, got {pair[0]:g} {pair[1]:g}")
    if not (np.isfinite(route_jitter) and route_jitter >= 0):
        raise DatasetError(f"--route-jitter: expected a distance of at least 0 m, got {route_jitter}")
    if compression not in COMPRESSIONS:
        raise DatasetError(f"--compression: expected one of {', '.join(COMPRESSIONS)}, got {compression}")
    out = _out_path(out)
    command = command_line(names, episodes, seed, duration, rate, density, route_jitter, compression)
    planned = plan(scenarios, episodes, seed, duration, rate, density, route_jitter)
    _check_frames(planned, duration)
    _check_variations(planned, allow_large, rate, density, route_jitter)
    made = _open_folder(out)
    try:
        done = _check_folder(out, command)
        had_manifest = (out / MANIFEST).exists()
        _probe(out)
    except OSError as e:
        _remove_made(made)
        raise DatasetError(f"--out {out}: {e.strerror or e}; expected a folder to write the dataset to") from None
    except BaseException:
        _remove_made(made)
        raise
    jobs = [job for job in planned if job["id"] not in done]
    header = {"format_version": FORMAT_VERSION, "crowdsim_version": __version__, "command": command,
              "root_seed": seed, "episodes_planned": episodes}
    frames_total = sum(round(job["duration"] * job["spec"].sensors.lasers[0].rate)
                       if job["spec"].sensors.lasers else 0 for job in jobs)
    episodes_bar = tqdm(total=episodes, initial=len(done), unit="episode", disable=not progress, desc="episodes",
                        position=0)
    frames_bar = tqdm(total=frames_total, unit="frame", disable=not progress, desc="frames", position=1)
    try:
        _write_manifest(out, header, done)
        run = _run_with_ray if ray_address is not None else _run_with_processes
        results = run(jobs, out, compression, workers, ray_address, frames_bar)
        try:
            for entry in results:
                done[entry["id"]] = entry
                _write_manifest(out, header, done)
                episodes_bar.update()
        finally:
            results.close()  # stops the workers when the loop ends early
    except BaseException as e:
        with stops_held():
            frames_bar.close()
            episodes_bar.close()
            kept = _kept(out, _tidy(out, header, done, made, had_manifest), episodes, made)
        if isinstance(e, DiskFullError):  # from a worker too, where the error it came from stayed behind
            raise DatasetError(f"--out {out}: {_space(getattr(e, 'reason', 'no space'))} while writing "
                               f"{getattr(e, 'episode', 'an episode')}, whose partial files were removed; "
                               f"{kept}") from None
        full = _disk_full(e) if isinstance(e, Exception) else None
        if full is not None:  # the manifest's update
            raise DatasetError(f"--out {out}: {_space(full)} while writing {MANIFEST}; {kept}") from None
        try:
            e.kept = kept
        except AttributeError:
            pass
        raise
    frames_bar.close()
    episodes_bar.close()
    return json.loads((out / MANIFEST).read_text())


def _run_with_processes(jobs, out, compression, workers, _address, frames_bar):
    """Episodes in this process (one worker) or in ``workers`` spawned processes; yields each entry as it ends.
    An error in one episode stops the others (the complete ones are yielded first); so does anything that stops
    the caller's loop (the generator closed), or an interruption."""
    if workers == 1:
        for job in jobs:
            yield make_episode(job, out, compression, lambda stamp: frames_bar.update())
        return
    counter = get_context("spawn").Value("q", 0)
    with process_pool(workers, _start_worker, (counter,)) as pool:  # ends the workers on any exception
        pending = {pool.submit(_run_local, job, str(out), compression) for job in jobs}
        while pending:
            finished, pending = wait(pending, timeout=0.5, return_when=FIRST_COMPLETED)
            frames_bar.update(counter.value - frames_bar.n)
            failed = [future for future in finished if future.exception() is not None]
            for future in finished:
                if future.exception() is None:
                    yield future.result()
            if failed:
                raise failed[0].exception()


def _run_with_ray(jobs, out, compression, workers, address, frames_bar):
    """Episodes as Ray tasks, on the cluster at ``address`` or a local one ("local"); yields each entry as it ends
    (crowdsim/workers.py: on an error or an interruption the tasks not finished are cancelled)."""
    with ray_session(address, workers) as ray:
        task = ray.remote(num_cpus=1)(make_episode)
        for _, entry in ray_results(ray, [task.remote(job, out, compression) for job in jobs]):
            frames_bar.update(entry["frames"])
            yield entry

"""``crowdsim dataset generate``: N episodes of one or more scenarios, in parallel and resumably.

Episode k runs scenario k mod S (of the S named) at the seed drawn from the k-th child of ``SeedSequence(root)``;
its variations (crowd rate and density, the robot's route) come from that child too, so an episode's bytes depend on
the command and k alone, never on the workers, the engine or the order of completion.

Each episode is written into a hidden temporary folder in the dataset and renamed into place when complete; the
manifest, rewritten atomically after each, lists only complete episodes with every file's size and sha256. Running
the command again verifies those checksums and redoes only what is missing or corrupt: a ``kill -9`` anywhere loses
at most the episodes in flight. A folder that holds anything else, or a dataset of a different command, is refused.
"""

from __future__ import annotations

import copy
import json
import os
import shutil
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from multiprocessing import get_context
from pathlib import Path

import numpy as np
from tqdm import tqdm

from scenarios.geometry import closest_on_segments, wall_segments

from .. import __version__
from .episode import COMPRESSIONS, write_episode
from .layout import (EPISODE_FILES, DatasetError, FORMAT_VERSION, MANIFEST, SPLITS, episode_id, episode_seeds, file_digest,
                     in_mini, scenario_digest, split_of)

TMP_PREFIX = ".tmp-"
ROUTE_CLEARANCE = 0.3  # m beyond the robot's radius a jittered waypoint keeps from every wall, or it stays put


def vary(scenario: dict, rng: np.random.Generator, rate: tuple[float, float] | None,
         density: tuple[float, float] | None, route_jitter: float) -> tuple[dict, dict]:
    """The episode's scenario and what was drawn: every source's rate times one factor uniform in ``rate``; every
    agent cluster's and standing group's count times one factor uniform in ``density`` (rounded, at least 1); the
    robot's start and route waypoints each moved uniformly within a disc of ``route_jitter`` m, a waypoint kept
    where it would come within the robot's radius plus ROUTE_CLEARANCE of a wall. The draws are made in that order,
    each only when asked for, so adding one option leaves the others' draws as they were."""
    sc, drawn = copy.deepcopy(scenario), {}
    if rate is not None:
        f = float(rng.uniform(*rate))
        for source in sc["sources"]:
            source["rate"] *= f
        drawn["rate_scale"] = f
    if density is not None:
        f = float(rng.uniform(*density))
        for key in ("agents", "standing"):
            for cluster in sc.get(key) or []:
                cluster["count"] = max(1, int(round(cluster["count"] * f)))
        drawn["density_scale"] = f
    if route_jitter > 0:
        robot = sc["robot"]
        points = np.array([robot["start"][:2], *robot["route"]], float).reshape(-1, 2)
        r = route_jitter * np.sqrt(rng.uniform(size=len(points)))
        a = rng.uniform(0, 2 * np.pi, len(points))
        moved = points + np.column_stack([r * np.cos(a), r * np.sin(a)])
        walls = wall_segments(sc)
        if len(walls):
            clear = closest_on_segments(moved, walls)[1].min(axis=1) > robot["radius"] + ROUTE_CLEARANCE
            moved = np.where(clear[:, None], moved, points)
        robot["start"] = [float(moved[0, 0]), float(moved[0, 1]), robot["start"][2]]
        robot["route"] = moved[1:].tolist()
        drawn["route_offsets"] = (moved - points).tolist()
    return sc, drawn


def plan(scenarios: list[dict], episodes: int, seed: int, duration: float | None, rate, density,
         route_jitter: float) -> list[dict]:
    """Every episode's id, split, scenario (varied), seed and duration: a pure function of the arguments."""
    out = []
    for k in range(episodes):
        base = scenarios[k % len(scenarios)]
        sim_seed, rng = episode_seeds(seed, k)
        scenario, drawn = vary(base, rng, rate, density, route_jitter)
        scenario["seed"] = sim_seed
        out.append({"id": episode_id(k), "index": k, "split": split_of(k), "mini": in_mini(k),
                    "scenario": scenario["name"], "scenario_sha256": scenario_digest(base), "seed": sim_seed,
                    "variation": drawn, "duration": float(duration if duration is not None else base["duration"]),
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


def make_episode(job: dict, root: Path, compression: str, progress=None) -> dict:
    """Write one episode into a temporary folder under ``root`` and rename it into place; its manifest entry."""
    final = root / job["id"]
    tmp = root / f"{TMP_PREFIX}{job['id']}-{os.getpid()}"
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.mkdir()
    try:
        frames = write_episode(job["spec"], job["seed"], job["duration"], tmp, compression, progress)
        files = _episode_files(tmp)
        shutil.rmtree(final, ignore_errors=True)  # a corrupt copy found by the check
        tmp.rename(final)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    entry = {k: job[k] for k in ("id", "split", "mini", "scenario", "scenario_sha256", "seed", "variation",
                                 "duration")}
    return {**entry, "frames": frames, "status": "complete", "files": files}


_worker: dict = {}


def _start_worker(counter) -> None:
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
    tmp.write_text(json.dumps(manifest, indent=1) + "\n")
    os.replace(tmp, root / MANIFEST)


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


def generate(scenarios: list[dict], names: list[str], out: Path, episodes: int, seed: int = 0,
             duration: float | None = None, workers: int = 1, ray_address: str | None = None,
             rate=None, density=None, route_jitter: float = 0.0, compression: str = "gzip",
             progress: bool = True) -> dict:
    """Generate (or complete) the dataset in ``out``; return its manifest."""
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
    out = Path(out)
    command = command_line(names, episodes, seed, duration, rate, density, route_jitter, compression)
    done = _check_folder(out, command)
    out.mkdir(parents=True, exist_ok=True)
    jobs = [job for job in plan(scenarios, episodes, seed, duration, rate, density, route_jitter)
            if job["id"] not in done]
    header = {"format_version": FORMAT_VERSION, "crowdsim_version": __version__, "command": command,
              "root_seed": seed, "episodes_planned": episodes}
    _write_manifest(out, header, done)
    frames_total = sum(round(job["duration"] * job["spec"]["sensors"]["lasers"][0]["rate"])
                       if job["spec"]["sensors"]["lasers"] else 0 for job in jobs)
    episodes_bar = tqdm(total=episodes, initial=len(done), unit="episode", disable=not progress, desc="episodes",
                        position=0)
    frames_bar = tqdm(total=frames_total, unit="frame", disable=not progress, desc="frames", position=1)
    try:
        run = _run_with_ray if ray_address is not None else _run_with_processes
        for entry in run(jobs, out, compression, workers, ray_address, frames_bar):
            done[entry["id"]] = entry
            _write_manifest(out, header, done)
            episodes_bar.update()
    finally:
        frames_bar.close()
        episodes_bar.close()
    return json.loads((out / MANIFEST).read_text())


def _run_with_processes(jobs, out, compression, workers, _address, frames_bar):
    """Episodes in this process (one worker) or in ``workers`` spawned processes; yields each entry as it ends."""
    counter = get_context("spawn").Value("q", 0)
    _start_worker(counter)
    if workers == 1:
        for job in jobs:
            entry = make_episode(job, out, compression, lambda stamp: frames_bar.update())
            yield entry
        return
    with ProcessPoolExecutor(workers, mp_context=get_context("spawn"), initializer=_start_worker,
                             initargs=(counter,)) as pool:
        pending = {pool.submit(_run_local, job, str(out), compression) for job in jobs}
        while pending:
            finished, pending = wait(pending, timeout=0.5, return_when=FIRST_COMPLETED)
            frames_bar.update(counter.value - frames_bar.n)
            for future in finished:
                yield future.result()


def _run_with_ray(jobs, out, compression, workers, address, frames_bar):
    """Episodes as Ray tasks, on the cluster at ``address`` or a local one ("local")."""
    try:
        import ray
    except ImportError:
        raise DatasetError("--ray: Ray is not installed; expected pip install -e \".[ray]\"") from None
    started = not ray.is_initialized()
    if started:
        env = {"MUJOCO_GL": os.environ.get("MUJOCO_GL", "")}
        ray.init(address=None if address == "local" else address, num_cpus=workers if address == "local" else None,
                 runtime_env={"env_vars": env}, include_dashboard=False, log_to_driver=False)
    task = ray.remote(num_cpus=1)(make_episode)
    try:
        pending = [task.remote(job, out, compression) for job in jobs]
        while pending:
            finished, pending = ray.wait(pending, num_returns=1, timeout=0.5)
            for ref in finished:
                entry = ray.get(ref)
                frames_bar.update(entry["frames"])
                yield entry
    finally:
        if started:
            ray.shutdown()

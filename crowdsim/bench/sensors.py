"""``crowdsim bench sensors``: the cost of one call of each sensor with 100 and 500 people, MuJoCo's batched ray call
beside ``mj_multiRay``, and the robot's sensor mix against real time, side by side in one run.

The people walk the bench hall (crowdsim/bench.py) and are synced into the scene once; the robot stands in the
middle facing +x; the mix is also measured in the airport with 100 of its people (``airport_mix_ms``). The sensor
mix is the issue's: two back-to-back 70 cm lasers at 25 Hz, a 160 x 120 depth camera
at 15 Hz and a 320 x 240 wall camera at 10 Hz; its real-time factor is one simulated second over the cost of its
calls in that second, as the loop makes them: 25 syncs of the lasers' torso-only scene and 25 casts of
both lasers (sensors/laser.py, LaserArray), and for the cameras' scene of whole people a sync at each tick a camera
is due (20 a second), 15 depth images with the visible share of each person shown (``DepthCamera.visibility``, which
the loop takes of every depth image) and 10 wall images.
"""

from __future__ import annotations

import platform

import numpy as np

from scenarios.format import DEPTH_CAMERA
from scenarios.schema import validate

from .common import HALL, populated_crowd, rate, write_figures
from .common import add_arguments  # noqa: F401  (its flags: those every benchmark takes)

DEPTH = validate({"name": "front_depth", "preset": "kinect_160", "position": [0.45, 0.0, 1.45], "pitch": 0.1},
                 DEPTH_CAMERA, "<bench>")
DEPTH_640 = dict(DEPTH, name="front_depth_640", width=640, height=480)
WALL = {"name": "wall_cam", "position": [1.0, 1.0, 4.0], "yaw": float(np.pi / 4), "pitch": 0.35, "fovy_deg": 45.0,
        "width": 320, "height": 240, "rate": 10.0, "rgb": True}
LASER_HZ, DEPTH_HZ, WALL_HZ = 25.0, 15.0, 10.0


def _setup(n_people: int, parts, cameras: bool):
    from sensors import Laser, Scene
    from sensors.body import body_scale

    crowd, scenario = populated_crowd(n_people)
    for _ in range(25):  # a second of walking: legs mid-stride, headings set
        crowd.step(0.04)
    scene = Scene(crowd.walls, 0.425, n_people, parts, robot_cameras=[DEPTH, DEPTH_640] if cameras else [],
                  wall_cameras=[WALL] if cameras else [])
    pose = np.array([HALL / 2, HALL / 2, 0.0])
    scale = body_scale(crowd.id, crowd.radius)
    sync = lambda: scene.sync(pose, crowd.id, crowd.pos, crowd.vel, crowd.walked, scale)  # noqa: E731
    sync()
    lasers = [Laser(scene=scene, rng=np.random.default_rng(k), **p.params)
              for k, p in enumerate(scenario.sensors.lasers)]
    return scene, pose, sync, lasers, scenario


def per_call_ms(n_people: int, quick: bool) -> dict:
    """Milliseconds per call of each sensor with ``n_people`` in the scene."""
    from scenarios.format import LASER
    from scenarios.schema import validate
    from sensors import Laser
    from sensors.camera import DepthCamera, WallCamera
    from sensors.laser import LaserArray

    reps = 10 if quick else 60
    out = {}
    scene, pose, sync, lasers, _ = _setup(n_people, {"torso"}, cameras=False)
    out["scene_sync_torsos_only"] = 1e3 / rate(sync, reps)
    out["laser_70cm_torsos_only"] = 1e3 / rate(lambda: lasers[0].scan(0.0, pose), reps)
    both = LaserArray(lasers, scene)
    out["two_lasers"] = 1e3 / rate(lambda: both.scan(0.0, pose, [0, 1]), reps)
    scene, pose, sync, lasers, _ = _setup(n_people, ("torso", "head", "legs"), cameras=True)
    out["scene_sync"] = 1e3 / rate(sync, reps)
    out["laser_70cm_full_bodies"] = 1e3 / rate(lambda: lasers[0].scan(0.0, pose), reps)
    leg = Laser(scene=scene, rng=np.random.default_rng(0),
                **validate({"name": "leg_laser", "mount": [0.25, 0, 0], "preset": "sick_s300"}, LASER, "<bench>"))
    out["laser_38cm_s300_full_bodies"] = 1e3 / rate(lambda: leg.scan(0.0, pose), reps)
    depth = DepthCamera(scene=scene, rng=np.random.default_rng(0), **DEPTH)
    out["depth_160x120"] = 1e3 / rate(lambda: depth.render(0.0), max(3, reps // 3))
    image = depth.render(0.0)
    out["depth_160x120_visibility"] = 1e3 / rate(lambda: depth.visibility(image), max(3, reps // 3))
    depth640 = DepthCamera(scene=scene, rng=np.random.default_rng(0), **DEPTH_640)
    out["depth_640x480"] = 1e3 / rate(lambda: depth640.render(0.0), max(2, reps // 10))
    wall = WallCamera(scene=scene, **WALL)
    out["wall_320x240_rgb_boxes"] = 1e3 / rate(lambda: wall.render(0.0), max(3, reps // 3))
    out["renderer"] = depth.backend
    out["people_in_wall_image"] = int(len(wall.render(0.0).ids))
    return out


def batched_rays_us(n_people: int, quick: bool) -> dict:
    """Two back-to-back lasers' 762 rays: two mj_multiRay calls (one origin each) against one call of MuJoCo's
    batched ``mujoco.batch.Batch.ray`` with an origin per ray, on one and on two threads."""
    import mujoco
    from mujoco import batch

    scene, pose, sync, lasers, _ = _setup(n_people, {"torso"}, cameras=False)
    origins, dirs = [], []
    for laser in lasers:
        p = laser.pose_in(pose)
        a = p[2] + laser.angles
        dirs.append(np.stack([np.cos(a), np.sin(a), np.zeros_like(a)], 1))
        origins.append(np.tile([p[0], p[1], laser.height], (laser.n_beams, 1)))
    reps = 20 if quick else 200
    multiray = 1e6 / rate(lambda: [laser.scan(0.0, pose) for laser in lasers], reps)
    out = {"two_mj_multiRay_calls": multiray}
    for threads in (1, 2):
        b = batch.Batch(scene.model, nsim=threads, nthread=threads)
        b.bind("mocap_pos")[:] = scene.data.mocap_pos
        b.bind("mocap_quat")[:] = scene.data.mocap_quat
        pnt = np.concatenate(origins).reshape(threads, -1, 3)  # the rays split over the simulations
        vec = np.concatenate(dirs).reshape(threads, -1, 3)
        dist, geom = b.ray(pnt, vec, flg_static=True, bodyexclude=scene.robot_body)
        ref = np.zeros(len(pnt.reshape(-1, 3)))
        for k, laser in enumerate(lasers):
            g, d = np.zeros(laser.n_beams, np.int32), np.zeros(laser.n_beams)
            mujoco.mj_multiRay(scene.model, scene.data, origins[k][0], dirs[k].ravel(), None, 1,
                               scene.robot_body, g, d, None, laser.n_beams, 1e4)
            ref[k * laser.n_beams:(k + 1) * laser.n_beams] = d
        agree = float(np.abs(np.where(dist.ravel() < 0, -1, dist.ravel()) - np.where(ref < 0, -1, ref)).max())
        out[f"one_Batch_ray_call_{threads}_thread"] = 1e6 / rate(lambda: b.ray(pnt, vec, bodyexclude=scene.robot_body),
                                                                   reps)
        out[f"max_range_difference_m_{threads}_thread"] = agree
    return out


def camera_ticks(tick: float = 1 / LASER_HZ, seconds: float = 1.0) -> int:
    """Ticks in ``seconds`` at which a camera is due, scheduled as the loop does (crowdsim/loop.py: a camera is due
    once the clock reaches its next time, which then moves on by its period): 20 a second for 15 and 10 Hz on
    0.04 s ticks, each one sync of the cameras' scene."""
    due, next_depth, next_wall = 0, 0.0, 0.0
    for k in range(int(round(seconds / tick))):
        stamp, hit = k * tick, False
        while next_depth <= stamp + 1e-9:
            next_depth, hit = next_depth + 1 / DEPTH_HZ, True
        while next_wall <= stamp + 1e-9:
            next_wall, hit = next_wall + 1 / WALL_HZ, True
        due += hit
    return due


def _mix_realtime(c: dict) -> tuple[float, float]:
    """Real-time factors of the two lasers alone and of the whole mix, from per-call milliseconds ``c``."""
    lasers_only = LASER_HZ * (c["scene_sync_torsos_only"] + c["two_lasers"]) / 1e3
    camera_syncs = camera_ticks()
    depth = c["depth_160x120"] + c["depth_160x120_visibility"]
    mix = lasers_only + (camera_syncs * c["scene_sync"] + DEPTH_HZ * depth
                         + WALL_HZ * c["wall_320x240_rgb_boxes"]) / 1e3
    return 1.0 / lasers_only, 1.0 / mix


def airport_mix_ms(quick: bool, people: int = 100) -> dict:
    """The sensor mix's calls in the airport (airport_disembarkation_cameras after its warm-up and until ``people``
    are alive: its walls, its robot at the start, its front 160 x 120 depth camera without colour and its
    north-west 320 x 240 wall camera), with the first ``people`` persons alive."""
    from pipeline.params import declared
    from scenarios import load_scenario
    from sensors.body import body_scale
    from sensors.camera import DepthCamera

    from crowdsim.loop import Simulation

    sim = Simulation(load_scenario("airport_disembarkation_cameras"))
    sim.warm_up()
    while len(sim.crowd.id) < people:
        sim.crowd.step(sim.dt, sim.robot.pose[:2], sim.robot.radius)
    agents = sim.crowd.states()
    pick = slice(0, people)
    person = (agents.id[pick], agents.position[pick], agents.velocity[pick], agents.walked[pick],
              body_scale(agents.id[pick], agents.radius[pick]))
    pose = sim.robot.pose
    reps = 10 if quick else 60
    # the mix: a depth camera without colour (the scenario's front camera has it), a wall camera with it
    depth = DepthCamera(scene=sim.camera_scene, rng=np.random.default_rng(0),
                        **{**declared(sim.depth_cameras[0]), "rgb": False})
    wall = sim.wall_cameras[0]
    sim.camera_scene.sync(pose, *person)
    image = depth.render(0.0)
    out = {"scene_sync_torsos_only": 1e3 / rate(lambda: sim.scene.sync(pose, *person), reps),
           "two_lasers": 1e3 / rate(lambda: sim.laser_array.scan(0.0, pose, [0, 1]), reps),
           "scene_sync": 1e3 / rate(lambda: sim.camera_scene.sync(pose, *person), reps),
           "depth_160x120": 1e3 / rate(lambda: depth.render(0.0), max(3, reps // 3)),
           "depth_160x120_visibility": 1e3 / rate(lambda: depth.visibility(image), max(3, reps // 3)),
           "wall_320x240_rgb_boxes": 1e3 / rate(lambda: wall.render(0.0), max(3, reps // 3)),
           "renderer": depth.backend, "people_in_wall_image": int(len(wall.render(0.0).ids))}
    return out


def run_sensor_benchmarks(json_path: str | None = None, quick: bool = False) -> dict:
    print(f"crowdsim bench sensors on {platform.processor() or platform.machine()}, Python "
          f"{platform.python_version()}{' (quick)' if quick else ''}")
    figures = {"per_call_ms": {}, "batched_rays_us": {}}
    for n in (100, 500):
        calls = figures["per_call_ms"][n] = per_call_ms(n, quick)
        print(f"\n{n} people (renderer: {calls['renderer']}; {calls['people_in_wall_image']} in the wall image)")
        for key, value in calls.items():
            if key not in ("renderer", "people_in_wall_image"):
                print(f"  {key:40s} {value:9.3f} ms per call", flush=True)
    rays = figures["batched_rays_us"] = batched_rays_us(100, quick)
    print("\n762 rays of two lasers, 100 people (torsos):")
    for key, value in rays.items():
        print(f"  {key:40s} {value:9.3g} {'m' if key.startswith('max') else 'us per call'}", flush=True)
    airport = figures["airport_per_call_ms"] = airport_mix_ms(quick)
    for place, c in (("bench hall", figures["per_call_ms"][100]), ("airport", airport)):
        lasers_only, mix = figures[f"realtime_{place.replace(' ', '_')}"] = _mix_realtime(c)
        print(f"\n100 people in the {place}, sensor cost per simulated second ({c['renderer']}; "
              f"{c['people_in_wall_image']} in the wall image):")
        print(f"  two lasers @25 Hz (torsos only)              {lasers_only:9.1f} x real time (target 20x)")
        print(f"  + 160x120 depth @15 Hz + 320x240 wall @10 Hz {mix:9.1f} x real time (target 5x)")
        if place == "airport":
            for key, value in c.items():
                if key not in ("renderer", "people_in_wall_image"):
                    print(f"    {key:40s} {value:9.3f} ms per call")
    write_figures(json_path, figures)
    return figures


def main(args) -> int:
    """``crowdsim bench sensors``."""
    from ..cli import check_json

    check_json(args)
    run_sensor_benchmarks(json_path=args.json, quick=args.quick)
    return 0

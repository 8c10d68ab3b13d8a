"""The gymnasium environments: the checker, determinism, the vector environments against the single one, the
observations' geometry, the reward terms and the episode ends."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from gymnasium.vector import AutoresetMode

import crowdsim  # noqa: F401  (registers the ids)
from crowdsim.envs.core import Config, Episodes
from crowdsim.envs.layouts import LAYOUTS, room_walls
from crowdsim.envs.navigate import CrowdEnv

MODES = ["truth", "laser", "tracks", ("truth", "laser", "tracks")]


@pytest.mark.parametrize("env_id", ["crowdsim/Navigate-v0", "crowdsim/Follow-v0"])
@pytest.mark.parametrize("mode", MODES)
def test_gymnasium_checker_passes(env_id, mode):
    env = gym.make(env_id, observation=mode, people=6, render_mode="rgb_array")
    check_env(env.unwrapped)
    env.reset(seed=0)
    frame = env.render()
    assert frame.dtype == np.uint8 and frame.ndim == 3 and frame.shape[2] == 3


def _rollout(env, seed, steps, actions):
    obs, _ = env.reset(seed=seed)
    out = [obs]
    rewards = []
    for t in range(steps):
        obs, reward, terminated, truncated, _ = env.step(actions[t])
        out.append(obs)
        rewards.append(reward)
        if terminated or truncated:
            obs, _ = env.reset()
            out.append(obs)
    return out, rewards


@pytest.mark.parametrize("mode", ["truth", ("laser", "tracks")])
def test_one_seed_gives_identical_observations_and_rewards_twice(mode):
    actions = np.random.default_rng(5).uniform(-1, 1, (200, 2))
    runs = [_rollout(gym.make("crowdsim/Navigate-v0", observation=mode, people=10), 7, 200, actions)
            for _ in range(2)]
    (obs_a, rew_a), (obs_b, rew_b) = runs
    assert rew_a == rew_b
    assert len(obs_a) == len(obs_b)
    for a, b in zip(obs_a, obs_b):
        for key in a:
            assert np.array_equal(a[key], b[key]), key


def test_another_seed_gives_another_crowd():
    env = gym.make("crowdsim/Navigate-v0")
    a, _ = env.reset(seed=1)
    b, _ = env.reset(seed=2)
    assert not np.array_equal(a["persons"], b["persons"])


@pytest.mark.parametrize("mode", ["truth", ("truth", "tracks")])
def test_native_vector_env_episodes_equal_the_single_envs(mode):
    """Sub-environment i of the vector env reset with seed s is the single env reset with seed s + i, through
    episode ends (next-step autoreset): observations, rewards and infos (``info_of``)."""
    from crowdsim.envs.navigate import info_of

    n, steps, seed = 3, 60, 11
    actions = np.random.default_rng(2).uniform(-1, 1, (steps, n, 2))
    vec = gym.make_vec("crowdsim/Navigate-v0", num_envs=n, vectorization_mode="vector_entry_point",
                       observation=mode, people=8, time_limit=4.0)
    obs, _ = vec.reset(seed=seed)
    vec_obs, vec_rewards, vec_done, vec_infos = [obs], [], [], []
    for t in range(steps):
        obs, reward, terminated, truncated, info = vec.step(actions[t])
        vec_obs.append(obs)
        vec_rewards.append(reward)
        vec_done.append(terminated | truncated)
        vec_infos.append(info)
    assert np.any(vec_done), "the time limit must end episodes within the test"
    for i in range(n):
        env = gym.make("crowdsim/Navigate-v0", observation=mode, people=8, time_limit=4.0)
        obs, _ = env.reset(seed=seed + i)
        expected, rewards, infos, restart = [obs], [], [], False
        for t in range(steps):
            if restart:  # next-step autoreset: this step resets, its action is ignored
                obs, info = env.reset()
                reward, restart = 0.0, False
            else:
                obs, reward, terminated, truncated, info = env.step(actions[t, i])
                restart = terminated or truncated
            expected.append(obs)
            rewards.append(reward)
            infos.append(info)
        for t, single in enumerate(expected):
            for key in single:
                assert np.array_equal(vec_obs[t][key][i], single[key]), (i, t, key)
        assert np.array_equal([r[i] for r in vec_rewards], rewards)
        for t, single in enumerate(infos):  # NaN metrics compare equal through their repr
            assert repr(info_of(vec_infos[t], i)) == repr(single), (i, t)


def test_same_step_autoreset_returns_the_final_observation_and_a_fresh_start():
    vec = gym.make_vec("crowdsim/Navigate-v0", num_envs=2, vectorization_mode="vector_entry_point", people=4,
                       time_limit=0.4, autoreset_mode=AutoresetMode.SAME_STEP)
    vec.reset(seed=0)
    vec.step(np.zeros((2, 2)))
    obs, _, _, truncated, info = vec.step(np.zeros((2, 2)))
    assert truncated.all() and info["_final_obs"].all()
    single = CrowdEnv(people=4, time_limit=0.4)
    single.reset(seed=0)
    single.step(np.zeros(2))
    final, *_ = single.step(np.zeros(2))
    fresh, _ = single.reset()
    assert np.array_equal(info["final_obs"][0]["persons"], final["persons"])
    assert np.array_equal(obs["persons"][0], fresh["persons"])
    assert info["final_info"]["episode_metrics"]["timeout"][0]


def test_async_vector_env_runs():
    vec = gym.make_vec("crowdsim/Navigate-v0", num_envs=4, vectorization_mode="async", people=5)
    try:
        obs, _ = vec.reset(seed=3)
        for _ in range(3):
            obs, reward, *_ = vec.step(vec.action_space.sample())
        assert obs["persons"].shape == (4, 10, 5) and reward.shape == (4,)
    finally:
        vec.close()


def test_disabled_autoreset_resets_only_the_masked_envs():
    vec = gym.make_vec("crowdsim/Navigate-v0", num_envs=2, vectorization_mode="vector_entry_point", people=4,
                       autoreset_mode=AutoresetMode.DISABLED)
    first, _ = vec.reset(seed=4)
    vec.step(np.ones((2, 2)))
    obs, _ = vec.reset(options={"reset_mask": np.array([False, True])})
    assert vec.unwrapped.episodes.elapsed.tolist() == [pytest.approx(0.2), 0.0]  # env 0 carried on, env 1 restarted
    assert obs["velocity"][0, 0] == pytest.approx(0.1)  # 0.5 m/s^2 for 0.2 s
    assert obs["velocity"][1].tolist() == [0.0, 0.0]
    assert not np.array_equal(obs["persons"][1], first["persons"][1])  # a new crowd from its own generator


def test_truth_observation_is_in_the_robot_frame_nearest_first():
    env = CrowdEnv(people=5, k_nearest=7)
    env.reset(seed=0)
    w = env.episodes.worlds
    w.robot_pose[0] = [6.0, 4.0, np.pi / 2]  # facing +y
    w.x[0] = [6.0, 3.0, 9.0, 6.0, 11.0]
    w.y[0] = [6.0, 4.0, 4.0, 1.0, 7.0]
    w.vx[0], w.vy[0] = 0.0, 0.0
    w.vy[0, 0] = 1.0  # walking +y: straight ahead of the robot, away from it
    obs = env.episodes.observe()
    persons, mask = obs["persons"][0], obs["persons_mask"][0]
    # forward is +y, left is -x: (6, 6) is 2 m ahead, (3, 4) 3 m to the left, (9, 4) 3 m to the right
    assert persons[0, :4] == pytest.approx([2.0, 0.0, 1.0, 0.0])
    assert sorted(map(tuple, persons[1:3, :2].round(6))) == [(0.0, -3.0), (0.0, 3.0)]
    assert persons[3, :2] == pytest.approx([-3.0, 0.0])
    assert persons[4, :2] == pytest.approx([3.0, -5.0])
    assert mask.tolist() == [1, 1, 1, 1, 1, 0, 0]
    assert persons[5:].sum() == 0
    w.goal[0] = [6.0, 8.0]
    assert env.episodes.observe()["goal"][0] == pytest.approx([4.0, 0.0])


def test_collision_terminates_with_the_collision_term():
    env = CrowdEnv(people=1, reward="crowdnav")
    env.reset(seed=0)
    w = env.episodes.worlds
    w.robot_pose[0] = [5.0, 4.0, 0.0]
    w.x[0], w.y[0], w.vx[0], w.vy[0] = 5.6, 4.0, 0.0, 0.0  # 0.6 m apart: 0.425 + 0.25 overlap
    w.gx[0], w.gy[0] = 5.6, 4.0  # standing at their goal
    _, reward, terminated, truncated, info = env.step(np.zeros(2))
    assert terminated and not truncated and info["collision"]
    assert reward == pytest.approx(-0.25)  # CrowdNav: collision alone, no discomfort on top
    assert info["episode_metrics"]["collision_person"]


def test_reaching_the_goal_terminates_with_success():
    env = CrowdEnv(people=0, reward="crowdnav")
    env.reset(seed=0)
    w = env.episodes.worlds
    w.goal[0] = w.robot_pose[0, :2] + [0.1, 0.0]
    env.episodes.distance[0] = 0.1
    _, reward, terminated, _, info = env.step(np.zeros(2))
    assert terminated and info["success"] and reward == pytest.approx(1.0)


def test_discomfort_is_crowdnavs_below_two_decimetres():
    env = CrowdEnv(people=1, reward="crowdnav")
    env.reset(seed=0)
    w = env.episodes.worlds
    w.robot_pose[0] = [5.0, 4.0, 0.0]
    w.crowd_p = w.crowd_p.replace(random_force=0.0, robot_strength=0.0)
    env.episodes.noise_rng[0] = np.random.default_rng(0)
    w.x[0], w.y[0], w.vx[0], w.vy[0] = 5.0, 4.775, 0.0, 0.0  # gap 0.1 m straight above the standing robot
    w.v0[0] = 0.0
    _, reward, terminated, _, info = env.step(np.zeros(2))
    assert not terminated
    gap = 0.2 - info["reward_terms"]["discomfort"] / 0.2  # (0.2 - gap) x 0.2 s
    assert gap == pytest.approx(0.1, abs=0.01)
    assert reward == pytest.approx(-0.5 * (0.2 - gap) * 0.2)


def test_time_limit_truncates():
    env = CrowdEnv(people=2, time_limit=1.0)
    env.reset(seed=0)
    ends = [env.step(np.zeros(2))[3] for _ in range(5)]
    assert ends == [False] * 4 + [True]


def test_robot_visibility_changes_how_people_react():
    """People keep clear of a visible robot; an invisible one (CrowdNav's published setting) is walked into."""
    closest = {}
    for visible in (True, False):
        ep = Episodes(1, Config(people=1, robot_visible=visible))
        ep.reset(0, np.random.default_rng(0))
        w = ep.worlds
        w.crowd_p = w.crowd_p.replace(random_force=0.0)
        w.robot_pose[0] = [6.0, 4.0, 0.0]
        w.x[0], w.y[0], w.gx[0], w.gy[0], w.v0[0] = 3.0, 4.3, 11.0, 4.3, 1.2  # passing 0.3 m off the robot's centre
        closest[visible] = w.tick(np.zeros((1, 2)), np.zeros((150, 1, 1), complex))[0].min()
    assert closest[False] < 0.0  # walked into: contacts push them out again each tick
    assert closest[True] > 0.0


@pytest.mark.parametrize("name", sorted(LAYOUTS))
def test_layouts_start_everyone_apart_inside_the_room_and_clear_of_the_robot(name):
    for seed in range(5):
        lay = LAYOUTS[name](12, np.random.default_rng(seed))
        d = np.linalg.norm(lay.start[:, None] - lay.start[None], axis=2) + np.eye(12) * 9
        assert d.min() > 0.5  # two radii
        assert (np.linalg.norm(lay.start - lay.robot_start[:2], axis=1) > 1.0).all()
        w, h = lay.size
        assert ((lay.start > 0.25) & (lay.start < [w - 0.25, h - 0.25])).all()
        assert len(room_walls(lay.size)) == 4


def test_too_many_people_is_one_clear_error():
    with pytest.raises(ValueError, match="people: layout 'passers_by' has room for at most"):
        CrowdEnv(people=500).reset(seed=0)


def test_options_change_the_scenario_and_the_people():
    env = CrowdEnv(people=3)
    obs, _ = env.reset(seed=0, options={"scenario": "circle_crossing", "people": 6})
    assert obs["persons_mask"].sum() == 6
    assert env.episodes.worlds.size == (14.0, 14.0)
    with pytest.raises(ValueError, match="options: unknown key"):
        env.reset(options={"humans": 3})


def test_rerun_recording_and_flattened_observations(tmp_path):
    from gymnasium.wrappers import FlattenObservation

    path = tmp_path / "env.rrd"
    env = FlattenObservation(gym.make("crowdsim/Navigate-v0", observation=("truth", "tracks"), people=4,
                                      record=str(path)))
    obs, _ = env.reset(seed=0)
    assert obs.shape == env.observation_space.shape == (2 + 2 + 10 * 5 + 10 + 10 * 8 + 10,)
    for _ in range(3):
        obs, *_ = env.step(env.action_space.sample())
        assert env.observation_space.contains(obs)
    env.close()
    assert path.stat().st_size > 1000


def test_zone_term_counts_the_robot_ahead_of_a_walker_not_behind():
    env = CrowdEnv(people=1)
    env.reset(seed=0)
    w = env.episodes.worlds
    w.vx[0], w.vy[0] = 1.0, 0.0  # walking +x at 1 m/s
    w.x[0], w.y[0] = 5.0, 4.0
    from crowdsim.envs.reward import in_zone

    for robot_x, expected in ((6.2, True), (5.4, True), (3.8, False), (6.2 + 0.5, False)):
        w.robot_pose[0] = [robot_x, 4.0, 0.0]
        assert in_zone(w)[0] == expected, robot_x  # the sector reaches R = 1.5 m ahead, the disc r = 0.5 m round
    w.robot_pose[0] = [5.0, 4.0 + 0.7, 0.0]  # beside, beyond the disc and outside the 30-degree sector
    assert not in_zone(w)[0]
    w.vx[0] = 0.1  # standing (below 0.25 m/s): the disc alone
    w.robot_pose[0] = [6.2, 4.0, 0.0]
    assert not in_zone(w)[0]


def test_follow_observes_the_tag_and_scores_the_band():
    env = CrowdEnv(task="follow", people=3, observation="truth")
    obs, _ = env.reset(seed=0)
    w = env.episodes.worlds
    # the target (person 0) starts 1.5 m ahead of the robot: within the tag's 0.5-4.5 m, inside the 1-2 m band
    assert obs["target"][:2] == pytest.approx([1.5, 0.0], abs=0.2)
    readings = []
    for _ in range(30):
        obs, reward, terminated, truncated, info = env.step(np.zeros(2))
        if obs["tag"][2]:
            truth = np.hypot(*(np.array([w.x[0, 0], w.y[0, 0]]) - w.robot_pose[0, :2]))
            readings.append(obs["tag"][0] - truth)
        d = np.hypot(w.x[0, 0] - w.robot_pose[0, 0], w.y[0, 0] - w.robot_pose[0, 1])
        inside = 1.0 <= d <= 2.0
        assert info["reward_terms"]["band"] == pytest.approx(0.2 if inside else 0.0)
        assert info["reward_terms"]["band_distance"] == pytest.approx(0.0 if inside else
                                                                      max(1.0 - d, d - 2.0) * 0.2)
    assert len(readings) > 5  # the target walks away from the standing robot: read until beyond 4.5 m
    assert abs(np.mean(readings)) < 0.5


def test_follow_episode_metrics_come_at_the_time_limit():
    env = CrowdEnv(task="follow", people=4, observation="tracks", time_limit=2.0)
    env.reset(seed=1)
    for _ in range(10):
        *_, terminated, truncated, info = env.step(np.zeros(2))
    assert truncated and not terminated
    m = info["episode_metrics"]
    assert m["success"] and 0.0 <= m["in_band_share"] <= 1.0 and m["target_losses"] >= 0


def test_vector_reset_takes_numpy_seeds_and_refuses_partial_option_changes():
    vec = gym.make_vec("crowdsim/Navigate-v0", num_envs=2, vectorization_mode="vector_entry_point", people=3)
    a, _ = vec.reset(seed=np.int64(5))
    b, _ = vec.reset(seed=5)
    assert np.array_equal(a["persons"], b["persons"])
    with pytest.raises(ValueError, match="expected no reset_mask"):
        vec.reset(options={"people": 4, "reset_mask": np.array([True, False])})


def test_random_force_drawn_in_blocks_is_the_per_step_draw():
    """Each world's noise generator draws NOISE_BLOCK steps at once: the numbers a draw a step gives, in order."""
    from crowdsim.envs.core import NOISE_BLOCK

    episodes = Episodes(2, Config(people=3))
    for k in range(2):
        episodes.reset(k, np.random.default_rng(k))
    twins = [g.spawn(4)[1] for g in (np.random.default_rng(0), np.random.default_rng(1))]  # reset's noise_rng
    scale = episodes.worlds.crowd_p.random_force
    for _ in range(NOISE_BLOCK + 3):
        draws = episodes._noise_draws()
        for k in range(2):
            assert np.array_equal(draws[k], twins[k].normal(0.0, scale, (episodes.ticks, 2, 3)))


def test_episode_log_grows_past_its_room_when_stepped_on():
    """A disabled-autoreset episode stepped on past its end keeps logging (the log doubles its room) and its
    metrics cover every entry."""
    vec = gym.make_vec("crowdsim/Navigate-v0", num_envs=1, vectorization_mode="vector_entry_point", people=2,
                       time_limit=0.4, autoreset_mode=AutoresetMode.DISABLED)
    vec.reset(seed=0)
    episodes = vec.unwrapped.episodes
    room = episodes.log["stamp"].shape[1]
    for _ in range(room + 1):
        vec.step(np.zeros((1, 2), np.float32))
    assert episodes.logged[0] == room + 2 and episodes.log["stamp"].shape[1] == 2 * room
    stamps = episodes.log["stamp"][0, :room + 2]
    assert np.allclose(np.diff(stamps), 0.2) and stamps[0] == 0.0
    assert isinstance(episodes.episode_metrics(0)["path_length"], float)


def _same_tree(a, b, where="info"):
    """Two vector infos alike: the same keys, arrays of the same dtype and values (NaN equal to NaN), observations
    (``final_obs``'s dicts) equal."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and set(a) == set(b), (where, sorted(a), sorted(b))
        for key in a:
            _same_tree(a[key], b[key], f"{where}[{key!r}]")
    elif isinstance(a, np.ndarray) and a.dtype == object:
        assert b.dtype == object and len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            assert (x is None) == (y is None), (where, i)
            if x is not None:
                _same_tree(x, y, f"{where}[{i}]")
    else:
        assert a.dtype == b.dtype and np.array_equal(a, b, equal_nan=a.dtype.kind == "f"), (where, a, b)


@pytest.mark.parametrize("mode", [AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP, AutoresetMode.DISABLED])
def test_the_native_vector_info_is_gymnasiums_sync_vector_info(mode):
    """The native vector environment's infos are what gymnasium's SyncVectorEnv gives for the same sub-environments,
    key for key: a nested dict (``reward_terms``, ``episode_metrics``, ``final_info``) a dict of arrays over the
    sub-environments with their masks, an episode's metrics where it ended, a restarting episode's info its reset's
    (none), and in SAME_STEP an ended one's last step only in ``final_info``."""
    kwargs = dict(num_envs=3, people=3, time_limit=0.6)
    native = gym.make_vec("crowdsim/Navigate-v0", vectorization_mode="vector_entry_point", autoreset_mode=mode,
                          **kwargs)
    sync = gym.make_vec("crowdsim/Navigate-v0", vectorization_mode="sync", vector_kwargs={"autoreset_mode": mode},
                        **kwargs)
    native.reset(seed=[0, 1, 2])
    sync.reset(seed=[0, 1, 2])
    actions = np.random.default_rng(0).uniform(-1, 1, (8, 3, 2)).astype(np.float32)
    ends, ended = 0, np.zeros(3, bool)
    for t, action in enumerate(actions):
        if mode == AutoresetMode.DISABLED and ended.any():  # the user resets what ended
            native.reset(options={"reset_mask": ended})
            sync.reset(options={"reset_mask": ended})
        _, _, terminated, truncated, got = native.step(action)
        want = sync.step(action)[4]
        ended = terminated | truncated
        _same_tree(got, want, f"step {t}")
        ends += int(got.get("_episode_metrics", np.zeros(3, bool)).sum()
                    + got.get("final_info", {}).get("_episode_metrics", np.zeros(3, bool)).sum())
    assert ends >= 6  # three episode ends each in at least two steps


def test_unscored_episodes_get_no_episode_metrics():
    """What a vector environment's restarting episodes report is dropped: their episode metrics are not computed."""
    episodes = Episodes(2, Config(people=2, time_limit=0.2))
    for k in range(2):
        episodes.reset(k, np.random.default_rng(k))
    _, _, truncated, step = episodes.step(np.zeros((2, 2)), unscored=np.array([True, False]))
    assert truncated.all()
    assert list(step.metrics) == [1] and "episode_metrics" not in step.of(0) and "episode_metrics" in step.of(1)

"""The PPO experiment's parts that need no stable-baselines3: the evaluation on held-out seeds and the curve."""

import numpy as np
import pytest

from crowdsim.experiments.ppo import evaluate, plot_curve


def test_a_robot_that_stands_still_times_out_every_evaluation_episode():
    result = evaluate(lambda obs: np.zeros(2), episodes=2, people=3, time_limit=0.4)
    assert result == {"episodes": 2, "success_rate": 0.0, "collision_rate": 0.0, "timeout_rate": 1.0,
                      "mean_return": pytest.approx(result["mean_return"])}
    assert abs(result["mean_return"]) < 0.5  # no progress, no goal, no collision: small discomfort or zone terms


def test_learning_curve_picture(tmp_path):
    steps = np.arange(1, 301) * 100
    curve = np.column_stack([steps, np.linspace(-5, 5, 300), np.arange(300) % 3 == 0])
    plot_curve(tmp_path / "curve.png", curve, random_success=0.05, trained_success=0.4)
    assert (tmp_path / "curve.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"

"""LandingBias: averaged swing landing error and the aim that cancels it."""

import numpy as np
import pytest

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.gait import LandingBias


def test_a_constant_overshoot_is_learned_and_cancelled() -> None:
    bias = LandingBias(gain=0.5, max_m=0.1)
    yaw = 0.4
    c, s = np.cos(yaw), np.sin(yaw)
    forward, left = np.array([c, s]), np.array([-s, c])
    foothold = np.array([1.0, 0.2, 0.0])
    for _ in range(30):  # the left foot lands 3 cm long and 1 cm outward of its aim
        aim = bias.aim("left", foothold, yaw)
        landed = aim.copy()
        landed[:2] += 0.03 * forward + 0.01 * left
        bias.measure("left", landed, aim, yaw)
    np.testing.assert_allclose(bias.bias, [0.03, 0.01], atol=1e-6)
    # Outward is mirrored for the right foot: its aim moves left (toward the other foot).
    aim_right = bias.aim("right", foothold, yaw)
    np.testing.assert_allclose(aim_right[:2], foothold[:2] - 0.03 * forward + 0.01 * left)
    assert aim_right[2] == foothold[2]


def test_bias_is_bounded_and_planar_ignores_sideways() -> None:
    bias = LandingBias(gain=1.0, max_m=0.02, planar=True)
    bias.measure("right", np.array([0.5, -0.3, 0.0]), np.zeros(3), 0.0)
    np.testing.assert_allclose(bias.bias, [0.02, 0.0])


@pytest.mark.parametrize(("gain", "max_m"), [(0.0, 0.1), (1.5, 0.1), (0.3, -0.01)])
def test_bad_settings_name_the_field(gain: float, max_m: float) -> None:
    with pytest.raises(ConfigError, match="landing_bias"):
        LandingBias(gain=gain, max_m=max_m)

"""Fixtures shared by the test modules: the registered robot models.

A :class:`RobotModel` is read-only in use (controllers, simulators and references make their
own MuJoCo / Pinocchio data), so each robot is loaded once per test session.
"""

from __future__ import annotations

import functools
from collections.abc import Callable

import pytest

from gaitnet_mpc.robots import ROBOTS, RobotModel, load_robot


@pytest.fixture(scope="session")
def robots() -> Callable[[str], RobotModel]:
    """``robots(name)``: the registered robot ``name``, loaded on first use."""
    return functools.cache(load_robot)


@pytest.fixture(scope="session")
def humanoid(robots: Callable[[str], RobotModel]) -> RobotModel:
    return robots("humanoid3d")


@pytest.fixture(scope="session")
def biped(robots: Callable[[str], RobotModel]) -> RobotModel:
    return robots("biped2d")


# module scope: a session-scoped parametrized fixture would make pytest regroup the tests of
# different modules by robot
@pytest.fixture(scope="module", params=sorted(ROBOTS))
def robot(request: pytest.FixtureRequest, robots: Callable[[str], RobotModel]) -> RobotModel:
    """Each registered robot in turn."""
    return robots(request.param)

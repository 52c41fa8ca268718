"""KDWalkConfig from a JSON object of overrides; nested objects override nested configs,
e.g. '{"lateral_reference": "lip", "low_level": {"stance_yaw_kp_nm_per_rad": 10}}'."""
from dataclasses import replace

from gaitnet_mpc.control.kd_walk import KDWalkConfig


def deep_replace(obj, overrides):
    kw = {}
    for k, v in overrides.items():
        cur = getattr(obj, k)
        if cur is None and k == "preview":
            from gaitnet_mpc.gait.preview import PreviewConfig

            cur = PreviewConfig()
        kw[k] = deep_replace(cur, v) if isinstance(v, dict) else (tuple(v) if isinstance(v, list) else v)
    return replace(obj, **kw)


def kd_config(overrides):
    return deep_replace(KDWalkConfig(), dict(overrides))


def kd_setup(course_name, dt, overrides, robot_name="humanoid3d", vx=0.75):
    """(robot, course, command, KDWalkController) with a fixed dt and the overrides."""
    from gaitnet_mpc.control.kd_walk import KDWalkController
    from gaitnet_mpc.mpc.sequential import FixedDt
    from gaitnet_mpc.robots import load_robot
    from gaitnet_mpc.runner.episode import Command
    from gaitnet_mpc.terrain import load_course

    robot, course, cmd = load_robot(robot_name), load_course(course_name), Command(vx_mps=vx)
    ctrl = KDWalkController(robot, course, cmd, dt_policy=FixedDt(dt), config=kd_config(overrides))
    return robot, course, cmd, ctrl

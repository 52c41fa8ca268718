"""KDWalkConfig from a JSON object of overrides; nested objects override nested configs,
e.g. '{"lateral_reference": "lip", "low_level": {"stance_yaw_kp_nm_per_rad": 10}}'."""
from dataclasses import replace

from gaitnet_mpc.control.kd_walk import KDWalkConfig


def deep_replace(obj, overrides):
    kw = {}
    for k, v in overrides.items():
        cur = getattr(obj, k)
        kw[k] = deep_replace(cur, v) if isinstance(v, dict) else (tuple(v) if isinstance(v, list) else v)
    return replace(obj, **kw)


def kd_config(overrides):
    return deep_replace(KDWalkConfig(), dict(overrides))

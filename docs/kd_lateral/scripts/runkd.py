"""usage: runkd.py COURSE DT DURATION '{json overrides of KDWalkConfig}' [robot] [vx]"""
import json, sys
from gaitnet_mpc.control.kd_walk import KDWalkController
from overrides import kd_config
from gaitnet_mpc.mpc.sequential import FixedDt
from gaitnet_mpc.robots import load_robot
from gaitnet_mpc.sim.episode import Command, run_episode
from gaitnet_mpc.sim.simulator import Simulator
from gaitnet_mpc.terrain import load_course
course_name, dt, dur = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
ov = json.loads(sys.argv[4]) if len(sys.argv) > 4 else {}
robot = load_robot(sys.argv[5] if len(sys.argv) > 5 else "humanoid3d")
vx = float(sys.argv[6]) if len(sys.argv) > 6 else 0.75
course = load_course(course_name); cmd = Command(vx_mps=vx)
cfg = kd_config(ov)
ctrl = KDWalkController(robot, course, cmd, dt_policy=FixedDt(dt), config=cfg)
s = run_episode(Simulator(robot, course), ctrl, cmd, dur, progress=False)
bad = [(f['foot'][0], f['pos_m'][:2]) for f in s['footholds'] if not f['allowed']]

print(course_name, dt, ov, "fell", s["fell"], s["fall_time_s"], "dist", round(s["distance_m"],2), "drift", s.get("lateral_drift_m"), "rmse", s["speed_rmse_mps"], "viol", s["foothold_violations"], "qps", s["mpc"].get("qps_per_full_mean"), "bad", bad)
ys = [f['pos_m'][1] for f in s['footholds']]
import numpy as _np
if len(ys) > 3: print("   step width mean/min [m]:", round(float(_np.mean(_np.abs(_np.diff(ys[2:])))),3), round(float(_np.min(_np.abs(_np.diff(ys[2:])))),3), "ys:", [round(y,3) for y in ys[:12]])

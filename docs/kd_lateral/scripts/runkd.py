"""usage: runkd.py COURSE DT DURATION '{json overrides of KDWalkConfig}' [robot] [vx]
Prints the outcome, the step width and the MPC statistics of one kd run."""
import json, sys
import numpy as np
from overrides import kd_setup
from gaitnet_mpc.runner.episode import run_episode
from gaitnet_mpc.sim.simulator import Simulator
course_name, dt, dur = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
ov = json.loads(sys.argv[4]) if len(sys.argv) > 4 else {}
robot_name = sys.argv[5] if len(sys.argv) > 5 else "humanoid3d"
vx = float(sys.argv[6]) if len(sys.argv) > 6 else 0.75
robot, course, cmd, ctrl = kd_setup(course_name, dt, ov, robot_name, vx)
s = run_episode(Simulator(robot, course), ctrl, cmd, dur, progress=False)
bad = [(f['foot'][0], f['pos_m'][:2]) for f in s['footholds'] if not f['allowed']]

print(course_name, dt, ov, "fell", s["fell"], s["fall_time_s"], "dist", round(s["distance_m"],2), "drift", s.get("lateral_drift_m"), "rmse", s["speed_rmse_mps"], "viol", s["foothold_violations"], "qps", s["mpc"].get("qps_per_full_mean"), "bad", bad)
ys = [f['pos_m'][1] for f in s['footholds']]
if len(ys) > 3: print("   step width mean/min [m]:", round(float(np.mean(np.abs(np.diff(ys[2:])))),3), round(float(np.min(np.abs(np.diff(ys[2:])))),3), "ys:", [round(y,3) for y in ys[:12]])
print("   mpc:", {k: (round(v, 4) if isinstance(v, float) else v) for k, v in s["mpc"].items() if not isinstance(v, (list, dict))})

"""one kd run with its MPC statistics: python mpcstat.py COURSE DT T '{overrides}' [robot] [vx]"""
import json, sys
from gaitnet_mpc.control.kd_walk import KDWalkController
from overrides import kd_config
from gaitnet_mpc.mpc.sequential import FixedDt
from gaitnet_mpc.robots import load_robot
from gaitnet_mpc.sim.episode import Command, run_episode
from gaitnet_mpc.sim.simulator import Simulator
from gaitnet_mpc.terrain import load_course
crs, dt, T = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
ov = json.loads(sys.argv[4]) if len(sys.argv) > 4 else {}
robot = load_robot(sys.argv[5] if len(sys.argv) > 5 else "humanoid3d"); course = load_course(crs)
vx = float(sys.argv[6]) if len(sys.argv) > 6 else 0.75
cmd = Command(vx_mps=vx)
ctrl = KDWalkController(robot, course, cmd, dt_policy=FixedDt(dt), config=kd_config(ov))
s = run_episode(Simulator(robot, course), ctrl, cmd, T, progress=False)
m = s["mpc"]
print(crs, dt, ov, "fell", s["fell"], s["fall_time_s"], "dist", round(s["distance_m"], 2), "rmse", round(s["speed_rmse_mps"], 3), "viol", s["foothold_violations"], {k: (round(v, 4) if isinstance(v, float) else v) for k, v in m.items() if not isinstance(v, (list, dict))})

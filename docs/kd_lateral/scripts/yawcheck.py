import json, sys
import numpy as np
from gaitnet_mpc.control.kd_walk import KDWalkController
from overrides import kd_config
from gaitnet_mpc.mpc.sequential import FixedDt
from gaitnet_mpc.robots import load_robot
from gaitnet_mpc.runner.episode import Command
from gaitnet_mpc.sim.simulator import Simulator
from gaitnet_mpc.terrain import load_course
crs, dt, T = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
ov = json.loads(sys.argv[4]) if len(sys.argv) > 4 else {}
robot = load_robot("humanoid3d"); course = load_course(crs)
ctrl = KDWalkController(robot, course, Command(0.75, 0, 0), dt_policy=FixedDt(dt), config=kd_config(ov))
sim = Simulator(robot, course); st = sim.state(); ctrl.reset(st)
rpy = []
while st.t_s < T:
    sim.step(ctrl.compute(st)); st = sim.state(); rpy.append(st.base_rpy_rad.copy())
    if sim.fall.fell: break
r = np.array(rpy[500:])
print(crs, ov, "t>0.5s: roll rms/max %.3f %.3f  pitch rms %.3f  yaw rms/max %.3f %.3f" % (np.sqrt((r[:,0]**2).mean()), np.abs(r[:,0]).max(), np.sqrt((r[:,1]**2).mean()), np.sqrt((r[:,2]**2).mean()), np.abs(r[:,2]).max()))

"""stance-foot travel and yaw change per stance (after 1 s): python slip.py COURSE DT T '{overrides}'"""
import json, sys
import numpy as np
from overrides import kd_setup
from gaitnet_mpc.sim.simulator import Simulator
crs, dt, T = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
ov = json.loads(sys.argv[4]) if len(sys.argv) > 4 else {}
robot, course, _, ctrl = kd_setup(crs, dt, ov)
sim = Simulator(robot, course); st = sim.state(); ctrl.reset(st)
start = None; last = -1; rows = []
while st.t_s < T:
    tau = ctrl.compute(st)
    s = ctrl.schedule
    if s.step_index != last:
        if start is not None and st.t_s > 1.0:
            f, p0, y0, p1, y1 = start
            rows.append((f, np.linalg.norm(p1[:2]-p0[:2]), abs(y1-y0)))
        last = s.step_index
        f = s.stance_foot
        start = [f, st.foot_pos_world_m[f].copy(), st.foot_yaw_rad[f], None, None]
    sim.step(tau); st = sim.state()
    f = start[0]; start[3] = st.foot_pos_world_m[f].copy(); start[4] = st.foot_yaw_rad[f]
    if sim.fall.fell: print("fell", st.t_s); break
d = np.array([r[1] for r in rows]); y = np.array([r[2] for r in rows])
print(ov, "stances", len(rows), "stance foot xy travel mean/max [m]", d.mean().round(4), d.max().round(4), "yaw change mean/max [rad]", y.mean().round(3), y.max().round(3))

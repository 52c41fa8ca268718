"""fall reason and the contacts at the fall: python why.py COURSE DT T '{overrides}'"""
import json, sys
import numpy as np
from overrides import kd_setup
from gaitnet_mpc.sim.simulator import Simulator
crs, dt, T = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
ov = json.loads(sys.argv[4]) if len(sys.argv) > 4 else {}
robot, course, _, ctrl = kd_setup(crs, dt, ov)
sim = Simulator(robot, course); st = sim.state(); ctrl.reset(st)
while st.t_s < T:
    sim.step(ctrl.compute(st)); st = sim.state()
    if sim.fall.fell:
        m, d = sim.model, sim.data
        print("fell", st.t_s, sim.fall.reason, "com", np.round(st.com_world_m,3), "rpy", np.round(st.base_rpy_rad,2))
        for i in range(d.ncon):
            c = d.contact[i]
            print("  contact", m.geom(c.geom1).name, m.body(m.geom_bodyid[c.geom1]).name, "|", m.geom(c.geom2).name, m.body(m.geom_bodyid[c.geom2]).name, np.round(c.pos,3))
        print("feet", {f: np.round(p,3) for f,p in st.foot_pos_world_m.items()})
        break
else:
    print("no fall")

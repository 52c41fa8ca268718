"""swing-foot contacts before the touchdown phase: python scuff.py COURSE DT T '{overrides}'
Prints every new contact of the swinging foot in the first 80 % of its swing: the
terrain geom it touches, the contact point and the foot's height above its lift-off."""
import json, sys
import numpy as np
from overrides import kd_setup
from gaitnet_mpc.sim.simulator import Simulator
crs, dt, T = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
ov = json.loads(sys.argv[4]) if len(sys.argv) > 4 else {}
robot, course, _, ctrl = kd_setup(crs, dt, ov)
sim = Simulator(robot, course); st = sim.state(); ctrl.reset(st)
prev = dict(st.foot_contact)
m, d = sim.model, sim.data
while st.t_s < T:
    sim.step(ctrl.compute(st)); st = sim.state()
    s = ctrl.schedule; sw = s.swing_foot
    if st.foot_contact[sw] and not prev[sw] and s.phase_in_step < 0.8:
        p = st.foot_pos_world_m[sw]
        hits = []
        for i in range(d.ncon):
            c = d.contact[i]
            b1, b2 = m.body(m.geom_bodyid[c.geom1]).name, m.body(m.geom_bodyid[c.geom2]).name
            if sw[0] in (b1 + b2).lower() or "foot" in (b1 + b2):
                hits.append((m.geom(c.geom1).name, m.geom(c.geom2).name, np.round(c.pos, 3).tolist()))
        print(f"t={st.t_s:.3f} {sw} phase {s.phase_in_step:.2f} foot ({p[0]:.3f},{p[1]:+.3f},{p[2]:.3f}) liftoff z {ctrl.liftoff[sw][2]:.3f} target {np.round(ctrl.swing.p1_world_m, 3).tolist()} contacts {hits}")
    prev = dict(st.foot_contact)
    if sim.fall.fell:
        print("fell", st.t_s); break

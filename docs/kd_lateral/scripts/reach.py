"""Is the swing target reachable? python reach.py COURSE DT T0 T1 '{overrides}'
Every 20 ms between T0 and T1: trunk roll/pitch/yaw, base position, the swing foot's
desired position and whether the leg IK reaches it from the measured base."""
import json
import sys
sys.path.insert(0, "docs/kd_lateral/scripts")
import numpy as np
from overrides import kd_setup
from gaitnet_mpc.sim.simulator import Simulator
from gaitnet_mpc.kinematics.leg_ik import whole_body_ik
crs, dt, T0, T1 = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4])
ov = json.loads(sys.argv[5]) if len(sys.argv) > 5 else {}
r, c, cmd, ctrl = kd_setup(crs, dt, ov)
sim = Simulator(r, c); st = sim.state(); ctrl.reset(st)
import pinocchio as pin
while st.t_s < T1:
    sim.step(ctrl.compute(st)); st = sim.state()
    if st.t_s > T0 and int(round(st.t_s*1000)) % 20 == 0:
        s = ctrl.schedule; sw = s.swing_foot
        des = ctrl.swing.position(s.time_in_step_s)
        q, v = r.mj_to_pin(st.qpos, st.qvel)
        base = q[:3].copy(); rot = pin.Quaternion(q[3:7]).toRotationMatrix()
        sol = whole_body_ik(r, base[None], rot[None], {sw: des[None]}, None, geometries=ctrl.low.geometries)
        print(f"t={st.t_s:.3f} rpy {np.round(st.base_rpy_rad,3)} base {np.round(base,3)} des {np.round(des,3)} reachable {getattr(sol,'reachable',None)}")

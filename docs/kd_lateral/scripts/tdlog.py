"""per-touchdown log: python tdlog.py COURSE DT T '{overrides}'"""
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
bnds = {}
ob = ctrl._bounds
def bspy(state, foot, nominal):
    r = ob(state, foot, nominal); bnds[foot] = r[foot]; return r
ctrl._bounds = bspy
sim = Simulator(robot, course)
st = sim.state(); ctrl.reset(st)
prev = dict(st.foot_contact)
while st.t_s < T:
    tau = ctrl.compute(st)
    s = ctrl.schedule; sw = s.swing_foot
    aim = ctrl.swing.position(1e9) if ctrl.swing is not None else None
    plan_td = ctrl.plan.touchdown(sw) if ctrl.plan is not None else None
    ph = s.phase_in_step
    sim.step(tau); st = sim.state()
    for f in ("left", "right"):
        if prev[f] and not st.foot_contact[f] and f == s.stance_foot and st.t_s > 1.8:
            p = st.foot_pos_world_m[f]
            print(f"  LOST stance {f[0]} t={st.t_s:.3f} ph {s.phase_in_step:.2f} at ({p[0]:.3f},{p[1]:+.3f},{p[2]:.3f}) rpy {np.round(st.base_rpy_rad,3)} wrench {np.round(ctrl.plan.iterate.f[ctrl.plan.stage_at(st.t_s), 0 if f=='left' else 1],1)}")
        if st.foot_contact[f] and not prev[f]:
            p = st.foot_pos_world_m[f]
            lo, hi = bnds.get(f, (np.full(3, np.nan), np.full(3, np.nan), None))[:2]
            a = aim if f == sw else np.full(3, np.nan)
            print(f"td {f[0]} t={st.t_s:.3f} ph {ph:.2f} aim ({a[0]:.3f},{a[1]:+.3f}) got ({p[0]:.3f},{p[1]:+.3f}) box x[{lo[0]:.2f},{hi[0]:.2f}] y[{lo[1]:+.2f},{hi[1]:+.2f}] com ({st.com_world_m[0]:.2f},{st.com_world_m[1]:+.3f}) v ({st.com_vel_world_mps[0]:.2f},{st.com_vel_world_mps[1]:+.2f}) nqps {ctrl.plan.n_qps if ctrl.plan else -1} conv {ctrl.plan.converged if ctrl.plan else None}")
    prev = dict(st.foot_contact)
    if sim.fall.fell: print("fell", st.t_s); break

"""dump one full solve's plan after T seconds of flat walking: python dump_plan.py DT T '{overrides}'"""
import json, sys
import numpy as np
from gaitnet_mpc.control.kd_walk import KDWalkController
from overrides import kd_config
from gaitnet_mpc.mpc.sequential import FixedDt
from gaitnet_mpc.robots import load_robot, FEET
from gaitnet_mpc.runner.episode import Command, run_episode
from gaitnet_mpc.sim.simulator import Simulator
from gaitnet_mpc.terrain import load_course
dt, T = float(sys.argv[1]), float(sys.argv[2])
ov = json.loads(sys.argv[3]) if len(sys.argv) > 3 else {}
robot = load_robot("humanoid3d"); course = load_course("flat"); cmd = Command(vx_mps=0.75)
ctrl = KDWalkController(robot, course, cmd, dt_policy=FixedDt(dt), config=kd_config(ov))
dumps = []
orig = ctrl._solve
def spy(state, full):
    orig(state, full)
    if full and state.t_s >= T and len(dumps) < 2 and ctrl.plan is not None:
        dumps.append((state.t_s, state.com_world_m.copy(), state.com_vel_world_mps.copy(),
                      {f: state.foot_pos_world_m[f].copy() for f in FEET}, ctrl.plan, ctrl.schedule.stance_foot))
ctrl._solve = spy
run_episode(Simulator(robot, course), ctrl, cmd, T + 0.8, progress=False)
m = robot.total_mass_kg
for t, com, vcom, feet, plan, stance in dumps:
    it, ref = plan.iterate, plan.reference
    print(f"\n=== t={t:.3f} stance={stance} com=({com[0]:.3f},{com[1]:.3f},{com[2]:.3f}) vcom=({vcom[0]:.3f},{vcom[1]:.3f}) feet L y={feet['left'][1]:.3f} R y={feet['right'][1]:.3f}")
    print(" converged", plan.converged, "nqps", plan.n_qps)
    st = plan.last_step.states
    print(" k  c(L,R)  pc_y    pcref_y  l_y    lref_y  kx     kxref  | pfL_y  pfR_y | fL(y,z)      fR(y,z)     | tauL_x tauR_x")
    for k in range(it.horizon):
        c = plan.contact[k]
        print(f"{k:2d}  {int(c[0])}{int(c[1])}    {it.p_com[k,1]:+.3f}  {ref.p_com_ref[k,1]:+.3f}  {st[k,7]:+.3f}  {ref.h_ref[k,1]:+.3f}  {st[k,9]:+.3f}  {ref.h_ref[k,3]:+.3f} | {it.p_foot[k,0,1]:+.3f}  {it.p_foot[k,1,1]:+.3f} | {it.f[k,0,1]:+6.1f} {it.f[k,0,2]:6.1f}  {it.f[k,1,1]:+6.1f} {it.f[k,1,2]:6.1f} | {it.tau[k,0,0]:+.2f} {it.tau[k,1,0]:+.2f}")
    print(f"{it.horizon:2d}        {it.p_com[-1,1]:+.3f}  {ref.p_com_ref[-1,1]:+.3f}  {st[-1,7]:+.3f}  {ref.h_ref[-1,1]:+.3f}  {st[-1,9]:+.3f}")
    # LIP check: for stance foot, force direction vs CoM-foot line
    z = np.mean(it.p_com[:, 2] - it.p_foot[:, :, 2].min(axis=1).mean())
    print(" mean com height above feet %.3f omega %.2f" % (z, np.sqrt(9.81 / z)))
    for k in range(it.horizon):
        for i in range(2):
            if plan.contact[k, i]:
                r = it.p_foot[k, i] - it.p_com[k]
                print(f"   k{k} foot{i}: r_y={r[1]:+.3f} r_z={r[2]:+.3f} f_y/f_z={it.f[k,i,1]/max(it.f[k,i,2],1e-6):+.3f} LIP f_y/f_z=r_y/r_z={r[1]/r[2]:+.3f}")

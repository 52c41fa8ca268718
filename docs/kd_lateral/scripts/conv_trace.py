"""trace sequential convergence of full solves after T s flat: python conv_trace.py DT T '{overrides}'"""
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
trace = []
sub = ctrl.mpc.subproblem
orig_sub = sub.solve
def sub_spy(*a, **k):
    st = orig_sub(*a, **k)
    dpf = st.delta_p_foot; dpc = st.delta_p_com
    trace.append((st.max_delta_pos_m, st.max_delta_force_n, st.max_delta_moment_nm,
                  np.abs(dpf[..., 0]).max(), np.abs(dpf[..., 1]).max(), np.abs(dpc[:, 1]).max(), np.abs(dpc[:, 0]).max(), st.solution.obj if hasattr(st.solution,'obj') else 0))
    return st
sub.solve = sub_spy
orig = ctrl._solve
n = [0]
def spy(state, full):
    trace.clear()
    orig(state, full)
    if full and state.t_s >= T and n[0] < 3:
        n[0] += 1
        print(f"t={state.t_s:.3f} nqps={len(trace)}")
        for j, r in enumerate(trace):
            if j < 12 or j % 5 == 0 or j == len(trace) - 1:
                print(f"  j{j:2d} pos {r[0]:.2e} F {r[1]:.2e} M {r[2]:.2e} | dpf_x {r[3]:.1e} dpf_y {r[4]:.1e} dpc_y {r[5]:.1e} dpc_x {r[6]:.1e} obj {r[7]:.4g}")
ctrl._solve = spy
run_episode(Simulator(robot, course), ctrl, cmd, T + 1.0, progress=False)

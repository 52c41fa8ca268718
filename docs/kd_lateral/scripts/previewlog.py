"""per-step preview log: python previewlog.py COURSE DT T '{overrides}'
Prints at each step start the measured CoM and stance foot and the preview plan."""
import json, sys
import numpy as np
from overrides import kd_setup
from gaitnet_mpc.sim.simulator import Simulator
crs, dt, T = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
ov = json.loads(sys.argv[4]) if len(sys.argv) > 4 else {}
robot, course, _, ctrl = kd_setup(crs, dt, ov)
sim = Simulator(robot, course); st = sim.state(); ctrl.reset(st)
orig = ctrl._start_step
def spy(state):
    orig(state)
    p = ctrl.preview
    s = ctrl.schedule
    head = f"t={state.t_s:.3f} st {s.stance_foot[0]}@({state.foot_pos_world_m[s.stance_foot][0]:.3f},{state.foot_pos_world_m[s.stance_foot][1]:+.3f}) com ({state.com_world_m[0]:.3f},{state.com_world_m[1]:+.3f}) v ({state.com_vel_world_mps[0]:.2f},{state.com_vel_world_mps[1]:+.2f})"
    if p is None:
        print(head, "PLAN NONE"); return
    fh = " ".join(f"{f[0]}({x:.2f},{y:+.2f})p{k}" for f, (x, y), k in zip(p.feet[1:4], p.foothold_m[1:4], p.patch[1:4]))
    print(head, "plan:", fh, "v", np.round(p.com_v_mps[::5, 0][:5], 2))
ctrl._start_step = spy
while st.t_s < T:
    sim.step(ctrl.compute(st)); st = sim.state()
    if sim.fall.fell:
        print("fell", st.t_s, sim.fall.reason); break

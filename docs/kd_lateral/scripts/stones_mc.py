"""Clean stepping-stone crossings under tiny initial perturbations, any KDWalkConfig overrides:
python stones_mc.py DT N 'JSON'  -> N runs with base x offsets eps_i = i * 1e-5 m (i = 1..N)"""
import sys, json
sys.path.insert(0, "docs/kd_lateral/scripts")
from concurrent.futures import ProcessPoolExecutor
def one(args):
    dt, ov, eps = args
    from overrides import kd_setup
    from gaitnet_mpc.sim.episode import run_episode
    from gaitnet_mpc.sim.simulator import Simulator
    import mujoco
    robot, course, cmd, ctrl = kd_setup("stepping-stones", dt, ov)
    sim = Simulator(robot, course)
    sim.data.qpos[0] += eps
    mujoco.mj_forward(sim.model, sim.data)
    s = run_episode(sim, ctrl, cmd, 8.0, progress=False)
    return (not s["fell"]) and s["foothold_violations"] == 0, s["fell"], round(s["distance_m"], 2), s["foothold_violations"]
dt, n, ov = float(sys.argv[1]), int(sys.argv[2]), json.loads(sys.argv[3])
with ProcessPoolExecutor(2) as pool:
    res = list(pool.map(one, [(dt, ov, i * 1e-5) for i in range(1, n + 1)]))
ok = sum(r[0] for r in res)
print(f"dt {dt} {ov}: clean crossings {ok}/{n}; no fall {sum(not r[1] for r in res)}/{n}; distances {[r[2] for r in res]}; violations {[r[3] for r in res]}", flush=True)

"""A hand-written dt policy in the Gymnasium environment (needs the ``gym`` extra).

    python examples/gym_dt_policy.py --duration 2.0

Each env step is one footstep: the agent gives that footstep's MPC sampling time dt
(the step lasts 5 dt) from the 16 Gait-Net features of its start; the ``kd`` MPC does the
rest. The rule below is only an illustration: the faster the CoM moves forward, the
shorter the step (from the longest dt at rest to the shortest at 0.6 m/s).
"""

import argparse

import numpy as np

from gaitnet_mpc.dataset.schema import FEATURE_NAMES
from gaitnet_mpc.envs.gym_env import DtPolicyEnv
from gaitnet_mpc.scenario import make_scenario

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--duration", type=float, default=2.0, help="simulated time [s]")
parser.add_argument("--course", default="flat", help="flat, stepping-stones, gap, ...")
args = parser.parse_args()

scenario = make_scenario(controller="kd", course=args.course, vx_mps=0.5, duration_s=args.duration)
env = DtPolicyEnv(scenario)
lo, hi = env.dt_bounds_s
vx = FEATURE_NAMES.index("com_vx_mps")  # CoM velocity along the heading [m/s]

obs, info = env.reset(seed=0)
total, done = 0.0, False
print("start [s]  CoM vx [m/s]  dt [ms]  reward [m]")
while not done:
    t_start, vx_start = info["t_s"], float(obs[vx])
    dt = hi - (hi - lo) * np.clip(vx_start / 0.6, 0.0, 1.0)
    obs, reward, terminated, truncated, info = env.step(np.array([dt], dtype=np.float32))
    total += reward
    done = terminated or truncated
    dt_ms = 1e3 * info["step_dt_s"]
    print(f"{t_start:9.3f}  {vx_start:12.3f}  {dt_ms:7.1f}  {reward:+10.3f}")

print(f"return {total:.3f} ({'fell' if terminated else 'upright'} at t = {info['t_s']:.2f} s)")

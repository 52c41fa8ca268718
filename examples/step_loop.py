"""Step an episode yourself and look at the robot between the steps.

    python examples/step_loop.py --duration 1.0

The same loop as ``gaitnet-mpc run`` (same ticks, logs and summary), run 50 ms at a time
by :class:`gaitnet_mpc.scenario.EpisodeStepper`.
"""

import argparse

from gaitnet_mpc.scenario import EpisodeStepper, make_scenario

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--duration", type=float, default=1.0, help="simulated time [s]")
parser.add_argument("--controller", default="kd", help="kd, gaitnet, srbm, stand, ...")
parser.add_argument("--vx", type=float, default=0.5, help="forward command [m/s]")
args = parser.parse_args()

scenario = make_scenario(controller=args.controller, vx_mps=args.vx, duration_s=args.duration)
stepper = EpisodeStepper(scenario)

print("   t [s]  CoM x [m]  step dt [ms]  stance  footsteps  next touchdown of the swing foot")
while not stepper.done:
    r = stepper.step(n_ticks=50)  # 50 control ticks of 1 ms
    touchdown = r.planned_footholds.get(r.swing_foot or "", None)
    where = "-" if touchdown is None else f"x = {touchdown[0]:.3f} m, y = {touchdown[1]:+.3f} m"
    print(
        f"{r.t_s:8.3f}  {r.state.com_world_m[0]:9.3f}  {1e3 * r.step_dt_s:12.0f}  "
        f"{r.stance_foot or '-':>6}  {r.steps_started:9d}  {where}"
    )

summary = stepper.summary()
print(f"outcome: {summary['outcome']}, {summary['distance_m']:.2f} m in {summary['duration_s']} s")

"""Can a fixed step time cross `stepping-stones`? The preview MILP over the whole course.

For each dt, start from a steady LIP gait at the commanded speed on the start platform
with the stance foot at x0 (one stride of start phases), and plan every step to the final
platform at once (gait/preview.py with a horizon covering the course: full preview, not
one-step). Counts the start phases with a plan that holds every bound (no slack) and
prints the speed range of the best one. Usage (repo root):

    .venv/bin/python docs/kd_lateral/scripts/lip_stones.py [--dts 0.045,0.055] [--cop 0.04]
"""

from __future__ import annotations

import argparse
import math
from dataclasses import replace

import numpy as np

from gaitnet_mpc.gait.preview import PreviewConfig, plan_preview
from gaitnet_mpc.mpc.srbm import GRAVITY_MPS2
from gaitnet_mpc.terrain import load_course


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dts", default="0.04,0.045,0.055,0.065,0.07")
    ap.add_argument("--z-c", type=float, default=0.555, help="CoM height [m] (humanoid3d)")
    ap.add_argument("--cop", type=float, default=PreviewConfig.cop_m, help="|CoP offset| [m]")
    ap.add_argument("--v-cmd", type=float, default=0.75)
    ap.add_argument("--phases", type=int, default=8, help="start phases over one stride")
    args = ap.parse_args()
    course = load_course("stepping-stones")
    w = math.sqrt(GRAVITY_MPS2 / args.z_c)
    for dt in (float(s) for s in args.dts.split(",")):
        T = 5 * dt
        L = args.v_cmd * T
        # steady symmetric LIP step: x - p = -L/2 at its start, v0 from periodicity
        v0 = w * math.sinh(w * T) * (-L / 2) / (1 - math.cosh(w * T))
        n_steps = int(math.ceil((3.6 - 0.0) / (0.5 * L))) + 2
        cfg = replace(PreviewConfig(cop_m=args.cop, n_steps=n_steps), time_limit_s=60.0)
        ok, best = 0, None
        for x0 in np.linspace(0.0, 2 * L, args.phases, endpoint=False):
            plan = plan_preview(
                course,
                cfg,
                com_m=np.array([x0 - L / 2, 0.0]),
                com_v_mps=np.array([v0, 0.0]),
                com_height_m=args.z_c,
                stance_foot="left",
                stance_m=np.array([x0, 0.065]),
                liftoff_m=np.array([x0 - L, -0.065]),
                time_left_s=T,
                dt_s=dt,
                v_cmd_mps=args.v_cmd,
                y_path_m=0.0,
                margin_m=(0.08, PreviewConfig.foothold_margin_y_m),  # as `kd --preview`
            )
            if plan is None or plan.max_violation_m > 1e-6:
                continue
            ok += 1
            on = (plan.com_m[:, 0] > 0.8) & (plan.com_m[:, 0] < 3.4)
            dev = float(np.abs(plan.com_v_mps[on, 0] - args.v_cmd).max())
            if best is None or dev < best[0]:
                best = (dev, plan.com_v_mps[on, 0].min(), plan.com_v_mps[on, 0].max())
        line = f"dt {dt:.3f} s (step {T:.3f} s): {ok}/{args.phases} start phases have a plan"
        if best is not None:
            line += f"; best keeps vx in [{best[1]:.2f}, {best[2]:.2f}] m/s on the stones"
        print(line, flush=True)


if __name__ == "__main__":
    main()

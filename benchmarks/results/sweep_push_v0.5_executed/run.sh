#!/bin/bash
# The push sweep of the default controllers with pushes at the phase of each one's own step,
# from a worktree at 6e4adfb (git worktree add /tmp/wt_exec 6e4adfb).
cd /tmp/wt_exec
export PYTHONPATH=/tmp/wt_exec/src MUJOCO_GL=egl
/work/main/.venv/bin/python -c "from gaitnet_mpc.cli.main import entry; entry()" sweep push \
  --controllers gaitnet,kd@0.045,kd@0.055,kd@0.065,srbm --speeds 0.5 --workers 2 \
  --out /work/main/benchmarks/results/sweep_push_v0.5_executed/sweep
echo ALLDONE

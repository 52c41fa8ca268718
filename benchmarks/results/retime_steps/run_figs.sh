#!/bin/bash
# Fig. 9 and Fig. 1(e) with the step re-timing as gaitnet's default, from a worktree at
# 1d3b398 (git worktree add /tmp/wt_new 1d3b398).
cd /tmp/wt_new
export PYTHONPATH=/tmp/wt_new/src MUJOCO_GL=egl
PY=/work/main/.venv/bin/python
R=/work/main/benchmarks/results/retime_steps
$PY -m gaitnet_mpc.cli.main reproduce fig9 --no-video --out $R/fig9
$PY -m gaitnet_mpc.cli.main reproduce obstacle --no-video --out $R/obstacle
echo ALLDONE

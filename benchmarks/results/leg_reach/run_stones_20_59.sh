#!/bin/bash
# Seeds 20-59 of the stones with and without the reach rows, from a worktree at 624a9bc.
cd /tmp/wt_reach  # made by: git worktree add /tmp/wt_reach 624a9bc
export PYTHONPATH=/tmp/wt_reach/src MUJOCO_GL=egl
PY=/work/main/.venv/bin/python
R=/work/main/benchmarks/results/leg_reach
$PY benchmarks/gaitnet_runs.py --seeds 40 --seed-offset 20 --courses stepping-stones --no-flat --dts 0.045 --set keep_feet_in_reach=true --jobs 2 --out $R/stones_20_59.md
$PY benchmarks/gaitnet_runs.py --seeds 40 --seed-offset 20 --courses stepping-stones --no-flat --dts 0.045 --jobs 2 --out $R/stones_20_59_default.md
echo ALLDONE

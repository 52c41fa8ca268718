#!/bin/bash
# The README's soak (200 random long episodes, five controllers) at b0e1962, from a worktree
# (git worktree add /tmp/wt_soak b0e1962). Resumable: run again to continue.
cd /tmp/wt_soak
export PYTHONPATH=/tmp/wt_soak/src MUJOCO_GL=egl OMP_NUM_THREADS=1
R=/work/main/benchmarks/results/soak_b0e1962
/work/main/.venv/bin/python benchmarks/soak.py --profile long --episodes 200 --workers 2 --out $R/soak.md
echo ALLDONE

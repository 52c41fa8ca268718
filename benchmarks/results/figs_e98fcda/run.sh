#!/bin/bash
# Figs. 7, 8, 10 and 11 at today's defaults (reach rows, step re-timing, the fallback fix),
# from a worktree at e98fcda (git worktree add /tmp/wt_figs e98fcda).
cd /tmp/wt_figs
export PYTHONPATH=/tmp/wt_figs/src MUJOCO_GL=egl OMP_NUM_THREADS=1
PY=/work/main/.venv/bin/python
R=/work/main/benchmarks/results/figs_e98fcda
for f in fig7 fig8 fig11 fig10; do
  /usr/bin/time -f "$f %e s" $PY -m gaitnet_mpc.cli.main reproduce $f --no-video --workers 1 --no-progress --out $R/$f
done
echo ALLDONE

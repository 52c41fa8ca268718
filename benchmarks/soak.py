"""The soak test's command line: many random short episodes, counting crashes
(:mod:`gaitnet_mpc.experiments.soak` has the engine and its documentation). Run::

    MUJOCO_GL=egl .venv/bin/python benchmarks/soak.py --episodes 1000 --workers 2 \
        [--backend process|ray] [--seed 0] [--out benchmarks/results/soak.md]
"""

import sys

from gaitnet_mpc.experiments.soak import main

if __name__ == "__main__":
    sys.exit(main())

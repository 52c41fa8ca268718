"""``python -m gaitnet_mpc.experiments.soak``: the same as ``benchmarks/soak.py``."""

import sys

from gaitnet_mpc.experiments.soak.cli import main

if __name__ == "__main__":  # not in the spawned workers, which import this as __mp_main__
    sys.exit(main())

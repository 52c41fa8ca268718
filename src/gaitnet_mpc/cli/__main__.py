"""``python -m gaitnet_mpc.cli``: the same as ``gaitnet-mpc``."""

import sys

from gaitnet_mpc.cli.main import main

sys.exit(main())

"""``python -m gaitnet_mpc.cli``: the same as ``gaitnet-mpc``."""

from gaitnet_mpc.cli.main import entry

entry()

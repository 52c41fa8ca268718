"""The command line, ``gaitnet-mpc SUB-COMMAND``: one thin module per sub-command, each
``add_parser(sub)`` and ``main(args) -> exit code``; :mod:`gaitnet_mpc.cli.main` puts them
together."""

from gaitnet_mpc.cli.main import build_parser, main

__all__ = ["build_parser", "main"]

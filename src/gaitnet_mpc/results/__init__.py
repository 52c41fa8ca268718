"""Results a person looks at: plots of one run folder and comparisons of several.

* :mod:`gaitnet_mpc.results.rundir`: reading a run folder (``summary.json``, ``log.csv``,
  ``mpc_log.csv``, ``course.json``) and atomic writes of figures and tables.
* :mod:`gaitnet_mpc.results.plots`: the PNGs of ``<run>/plots/`` (``gaitnet-mpc plot``).
* :mod:`gaitnet_mpc.results.compare`: one figure and one table over several runs
  (``gaitnet-mpc compare``).

Plotting uses matplotlib's object-oriented API with the Agg canvas (no pyplot, no global
backend switch), so importing this package does not touch matplotlib's global state.
"""

from gaitnet_mpc.results.rundir import RunFolder, load_run

__all__ = ["RunFolder", "load_run"]

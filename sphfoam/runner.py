"""The names scripts written against earlier versions of sphfoam import from here (nothing
inside the package imports this module). Running a case is now split by job:

* :mod:`sphfoam.timeloop` — the time loop (``run_case``, ``RunReport``);
* :mod:`sphfoam.setup.settling` — set-up (``setup_case``, settled when controlDict asks);
* :mod:`sphfoam.assemble` — a case's models into a simulation (``build_simulation``);
* :mod:`sphfoam.io.timedirs` — time directories (``write_time``, ``start_folder``, ...).

New code uses those modules, or the Python API (``sphfoam.run``, ``sphfoam.setup_case``).
"""

from sphfoam.assemble import build_simulation, check_wall_fields, selection
from sphfoam.io.timedirs import read_time_value, start_folder, write_time
from sphfoam.setup.settling import setup_case
from sphfoam.timeloop import Interrupted, Log, RunReport, run_case, write_schedule

__all__ = ["build_simulation", "check_wall_fields", "selection", "read_time_value",
           "start_folder", "write_time", "setup_case", "Interrupted", "Log", "RunReport",
           "run_case", "write_schedule"]

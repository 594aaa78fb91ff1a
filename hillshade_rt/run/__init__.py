"""Whole runs: DEM files in, georeferenced files and a report out. One function per command
(``shade``, ``sun_hours``, ``horizon``, ``describe``), each taking a config of plain data
(``run.config``) and returning the report; the command line and ``api`` build the configs.
No click below ``cli/``."""

from .config import (HorizonConfig, ReadOptions, RunOptions, ShadeConfig,  # noqa: F401
                     SunHoursConfig)
from .horizon import horizon  # noqa: F401
from .info import describe  # noqa: F401
from .shade import shade  # noqa: F401
from .sun_hours import sun_hours  # noqa: F401

"""The errors of runs that cannot be finished where they run (study/executor.py): a local worker process killed,
the Dask cluster lost. Each is one line naming the setting that chose the place, exit 2 (a ConfigError, as an
unreachable scheduler); the command keeps what completed, as for a Ctrl-C."""
from __future__ import annotations

from ..config_error import ConfigError


class RunsLost(ConfigError):
    """The runs cannot be finished where they run: one line opening with the setting that chose the place
    (``setting_name``) and exit 2; what completed before was given to ``on_done``, and the command keeps it as
    for a Ctrl-C."""

    setting_name = "jobs"

    def __init__(self, message: str, scheduler_alive: bool = False):
        super().__init__(f"{self.setting_name}: {message}", setting=self.setting_name)
        self.scheduler_alive = scheduler_alive


class ClusterLost(RunsLost):
    """The Dask cluster cannot finish the runs (its scheduler gone, no worker left, a run whose workers died
    again and again): named ``scheduler``, as an unreachable scheduler."""

    setting_name = "scheduler"


class PoolBroken(RunsLost):
    """A local worker process died (SIGKILL: the OOM killer, a ``kill -9``): the pool cannot go on."""

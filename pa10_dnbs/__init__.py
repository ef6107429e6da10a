"""pa10_dnbs: decentralized neural backstepping control of robot arms (the PA10-7CE by default; any serial
arm from its URDF, pa10_dnbs.arm)."""

__version__ = "0.1.0"


def _quiet_start_of_the_command() -> None:
    """When this process is the ``pa10-dnbs`` command: a Ctrl-C while its modules load ends it with one line and
    exit 130, not an import traceback (pa10_dnbs/interrupt.py). Any other importer keeps its own SIGINT."""
    import sys

    command = getattr(sys, "orig_argv", [])[1:3] == ["-m", "pa10_dnbs.cli"]   # python -m pa10_dnbs.cli
    if command or (sys.argv[:1] and sys.argv[0].endswith("pa10-dnbs")):       # the console script
        from .interrupt import quiet_start

        quiet_start()


_quiet_start_of_the_command()

"""pa10_dnbs: decentralized neural backstepping control of robot arms (the PA10-7CE by default; any serial
arm from its URDF, pa10_dnbs.arm)."""

__version__ = "0.1.0"


#: processes that are a command to the user (``python -m`` these): the CLI, and the robot node ``pa10-dnbs robot``
#: runs in the terminal's process group, so that the terminal's Ctrl-C reaches it while rclpy loads
COMMAND_MODULES = ("pa10_dnbs.cli", "pa10_dnbs.ros.mujoco_robot_node")
#: the nodes (``python -m`` these; each runs under ``ros.runtime.run_node``, whose handler takes over): one started
#: by hand (docs/graph.md) is in the terminal's group too
NODE_MODULES = tuple(f"pa10_dnbs.ros.{m}" for m in ("plant.node", "joint_controller_node", "reference_node",
                                                     "wire_monitor", "recorder_node", "live_observer_node",
                                                     "joint_bus_node"))


def _quiet_start_of_the_command() -> None:
    """When this process is the ``pa10-dnbs`` command or a node: a Ctrl-C while its modules load ends it with one
    line and exit 130, not an import traceback (pa10_dnbs/interrupt.py; a node's own handler takes over once it
    runs). Any other importer keeps its own SIGINT."""
    import sys

    argv = getattr(sys, "orig_argv", [])[1:3]
    module = argv[1] if argv[:1] == ["-m"] and argv[1:] else ""      # python -m pa10_dnbs.cli
    if module in NODE_MODULES:   # a node: its line names it
        from .interrupt import quiet_start

        quiet_start(module.removeprefix("pa10_dnbs.ros."))
    elif module in COMMAND_MODULES or (sys.argv[:1] and sys.argv[0].endswith("pa10-dnbs")):   # the console script
        from .interrupt import quiet_start

        quiet_start()


_quiet_start_of_the_command()

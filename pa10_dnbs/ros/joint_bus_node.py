"""joint_bus_node: the graph's plant side, in front of a robot this project does not simulate.

Between a robot speaking the standard interface (docs/your_robot.md: ``sensor_msgs/JointState`` states,
JointState or Float64MultiArray effort commands) and the per-joint topics of docs/graph.md, so that each
joint controller still sees only its own joint. It is the plant node with the physics replaced by the robot
(``robot_link.RemoteRobot``): the same per-joint state and effort topics, joint_states, robot_description,
effort gate, start handshake, lockstep loop and stats file, so the launcher, the recorder, the analysis and
the live view work unchanged. Step k of the graph is the k-th robot state the bus forwards. Lockstep
(``mode:=lockstep``, a robot that waits for commands): the efforts answering state k go out as one command, and
the bus waits for the robot's next state (the plant's lockstep loop, ``ros/plant/lockstep.py``). Paced
(``mode:=realtime``): the robot runs at its own rate and the bus follows it (``joint_bus_paced.py``).

Time: a robot that publishes /clock gives the graph its time (the bus publishes none; its first state must
be at time 0). Otherwise the bus publishes the graph's /clock (``clock_hz``), the robot's states counted from
the first. Whether the robot publishes /clock is asked of discovery once its first state is in, which may
not have matched its /clock publisher yet: the bus looks for one up to CLOCK_DISCOVERY_S before taking the
robot for one without.

Faults (one line ``ROBOT FAULT: ...``, the safe command of zero effort on every joint, exit 1): a joint of
the arm missing from the robot's state or named twice, a non-finite position or velocity, no state within
``robot_timeout_s`` (``start_timeout_s`` for the first; the line counts the states that came meanwhile with
the same or an earlier stamp), another publisher on the command topic (a second commander of the robot);
lockstep: a state off the dt grid, or one before the command of the previous one (a robot that does not wait).
Paced, the bus's last command (at the run's end, or stopped) is the same zero effort: the robot goes on applying
the last command it got, with no controller answering any more.
"""
from __future__ import annotations

import time
from typing import NoReturn

from ..wire.robot_interface import default_state_topic, parse_robot_command
from ..wire.steps import NS_PER_S
from ..settings import Settings
from .params import Param, ParameterError
from .plant.node import PARAMS as PLANT_PARAMS
from .plant.node import PlantNode
from .joint_bus_paced import run_paced
from .robot_link import RemoteRobot
from .runtime import stop_requested
from .endpoints import CLOCK

CLOCK_DISCOVERY_S = 0.5   # wall time [s] the bus looks for the robot's /clock publisher after its first state


def publisher_seen(count, within_s: float, poll_s: float = 0.02, now=time.monotonic, sleep=time.sleep) -> bool:
    """Whether ``count()`` (a topic's publishers, as discovery knows them) is > 0 within ``within_s`` [s] of wall
    time, asked every ``poll_s`` [s] (discovery matches a participant's endpoints one by one)."""
    end = now() + within_s
    while count() == 0:
        if now() >= end:
            return False
        sleep(poll_s)
    return True

PARAMS = {k: v for k, v in PLANT_PARAMS.items() if k != "interface"} | {
    "robot_timeout_s": Param(1.0, "wall time without a new state from the robot that makes it stale [s]", 0.0),
}


class JointBusNode(PlantNode):
    NODE_NAME = "joint_bus"
    PARAMS = PARAMS

    def _open_plant(self, settings: Settings) -> RemoteRobot:
        """The robot, once its first state is in (it sets whether the bus publishes /clock)."""
        p = self.p
        if not p["robot_timeout_s"] > 0:
            raise ParameterError(f"parameter robot_timeout_s must be > 0 s, got {p['robot_timeout_s']}")
        try:
            command = parse_robot_command(p["robot_command"], p["robot_command_topic"] or None)
        except ValueError as exc:
            raise ParameterError(f"parameter robot_command: {exc}") from None
        robot = RemoteRobot(self, settings.arm, self.clock_.dt_ns, p["robot_state_topic"] or default_state_topic(command),
                            command, p["robot_timeout_s"], stopped=stop_requested, lockstep=p["mode"] == "lockstep")
        self.robot = robot
        print(f"JOINT BUS {self.resolve_topic_name(robot.state_topic)} -> {self.resolve_topic_name(command.topic)} "
              f"({command.form}), joints "
              f"{', '.join(robot.joint_names)}", flush=True)
        if not robot.wait_first(p["start_timeout_s"]):
            raise KeyboardInterrupt  # stopped before the robot's first state: a clean stop (run_node: exit 0)
        # a second graph on a robot already past time 0 was taken for hardware once (1 in 13) when its /clock
        # publisher was not yet discovered: then it drove the robot beside the first graph's clock
        robot_clock = publisher_seen(lambda: self.count_publishers(CLOCK), CLOCK_DISCOVERY_S)
        sec, nanosec = robot.stamp
        if robot_clock:
            if sec or nanosec:
                robot.fault(f"the robot publishes /clock but its first state is at {sec + nanosec / NS_PER_S:.6f} s: "
                            "a robot with its own /clock must start at time 0 (restart its simulation)")
            p["clock_hz"] = 0.0  # the graph runs on the robot's /clock
        print(f"JOINT BUS first state at robot time {sec + nanosec / NS_PER_S:.6f} s; graph time from "
              + ("the robot's /clock" if robot_clock else f"the bus's /clock ({p['clock_hz']:g} Hz)"), flush=True)
        return robot

    def step_to_robot_state(self) -> None:
        """Paced: the robot's next state is in (its command went out already): count the step."""
        self.cpu.mark(self.gate.step)
        if self.gate.step >= self.n_steps:
            self.finished = True
            self.wall_end = time.perf_counter()

    def loop(self, executor, stop) -> None:
        if self.p["mode"] == "lockstep":
            return super().loop(executor, stop)
        if not self.wait_for_graph(executor, stop):
            return
        print("RUNNING plant", flush=True)
        self.wall_start = time.perf_counter()
        run_paced(self, executor, stop)

    def _close_plant(self) -> None:
        # paced, the robot would go on applying the last torque: zero effort last (unless a fault's safe command
        # was; a lockstep robot waits for its next command)
        if self.p["mode"] == "realtime" and self.robot.q is not None and not self.robot.last_was_safe:
            acked = self.robot.stop_command()
            print(f"JOINT BUS zero effort on every joint sent as the last command (paced robot; "
                  f"{'acknowledged' if acked else 'not acknowledged within 1 s'})", flush=True)
        print("STATS joint_bus: " + ", ".join(f"{k} {v}" for k, v in self.robot.counters().items()), flush=True)
        self.robot.close()

    def stats(self) -> dict:
        return super().stats() | {"robot": self.robot.counters()}


def main(args=None) -> NoReturn:
    from .runtime import exit_process, run_node

    exit_process(run_node(JointBusNode, args, params=PARAMS))


if __name__ == "__main__":
    main()

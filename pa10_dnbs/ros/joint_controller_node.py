"""joint_controller_node: one joint's DNBS (or PID) controller.

Node name ``joint_controller_<joint>`` unless remapped (``-r __node:=``).
Subscribes only to <ns>/<joint>/state and <ns>/<joint>/reference (<ns>: the
arm's namespace, /pa10 by default); publishes <ns>/<joint>/effort
(sensor_msgs/JointState, effort only) stamped with the
stamp of the state it answers, and its fault counters on /diagnostics. The
effort publisher is created when the first reference batch arrives, so a
plant that waits for every effort publisher starts with references in place;
answers are held until ``effort_subscribers`` subscriptions (the plant and
each recorder) have matched it, so a recorder never misses the first efforts
of a restarted controller (after ``match_timeout_s`` they go out regardless,
with a warning).

Each state is answered first and trained on after the effort is published
(``JointLoop.learn``), so the EKF update is not on the state-to-effort path.

Defensive: implausible states are answered with the last torque or zero
(JointLoop + StateGuard), the EKF guard resets a broken network; neither
ever lets a non-finite torque out. Faults configured in ``faults.effort`` are
injected on the effort link; ``faults.kill_controller_at_s`` makes the
process kill itself (SIGKILL) on the first state at or after that time
(``incarnation`` 0 only: the launcher numbers restarts 1, 2, ...).
With ``checkpoint_file`` the DNBS weights and covariances are saved every
``checkpoint.period_s`` of simulated time (each joint at its own phase of
the period: joint i of n at i/n of it) and at exit, and ``resume:=true``
starts from that file when it exists. Counters go to ``stats_file`` (JSON).
"""
from __future__ import annotations

from typing import NoReturn

import functools
import os
import re
import signal
import struct
import sys
from pathlib import Path

from rclpy.node import Node
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from ..atomic_file import write_json
from ..controller_factory import CONTROLLER_KINDS, build_guarded_controllers
from ..core.checkpoint import checkpoint_due, checkpoint_phase, load_checkpoint, save_checkpoint
from ..faults.faulty_link import faulty_link
from ..wire import joint_state_cdr
from ..wire.trajectory_cdr import decode_first_joint
from .diagnostics import DiagnosticsReporter, status, status_name
from ..loop.cpu_meter import CpuMeter
from ..loop.endpoint_match import MatchWait, Need
from ..loop.joint_loop import JointLoop
from ..loop.scheduling import apply_batch, apply_fifo, check_priority, policy_name
from .params import (MAX_QOS_DEPTH, RT_PRIORITY, SCHED_BATCH, SETTINGS_DEFAULTS, Param, ParameterError, check_choice,
                     cli_parameter, declare, declare_joint_settings)
from .ready import announce_when_ready
from .runtime import announce_ready, exit_process, run_node
from .endpoints import StepClock, effort_topic, loop_qos, reference_qos, reference_topic, state_topic
from .wall_timer import wall_timer

FAULT_KEYS = ("bad_states_nonfinite", "bad_states_position", "bad_states_speed", "nonfinite_torques",
              "ekf_resets_alpha", "ekf_resets_torque", "malformed_states")


PARAMS = {
    "config_file": SETTINGS_DEFAULTS,
    "joint": Param("", "the joint: one of the arm's actuated joints (required; names the node "
                       "joint_controller_<joint>)"),
    "controller": Param("dnbs", "dnbs or pid"),
    "reliability": Param("reliable", "state/effort QoS: reliable or best_effort"),
    "queue_depth": Param(10, "keep_last depth of the state subscription and effort publisher [messages]", 1,
                         MAX_QOS_DEPTH),
    "stats_file": Param("", "JSON file for the counters at exit; '' = none", writes=True),
    "checkpoint_file": Param("", "DNBS weights and covariances, saved every checkpoint.period_s [.npz]; '' = none",
                             writes=True),
    "resume": Param(False, "start from checkpoint_file when it exists"),
    "incarnation": Param(0, "0 = first start; n = the launcher's n-th restart", 0),
    "effort_subscribers": Param(1, "subscriptions (plant and recorders) to wait for before answering", 1),
    "match_timeout_s": Param(10.0, "wall time after which answers go out without them [s]", 0.0),
    "init_file": Param("", "warm start: DNBS checkpoint of an earlier run [.npz]; '' = cold start"),
    "rt_priority": RT_PRIORITY,
    "sched_batch": SCHED_BATCH,
}


class JointControllerNode(Node):
    def __init__(self, args=None):
        """``args``: the command line (default sys.argv); its ``-p joint:=J`` names the node joint_controller_J."""
        joint = cli_parameter(sys.argv if args is None else args, "joint")
        super().__init__(f"joint_controller_{joint}" if joint and re.fullmatch(r"[A-Za-z][A-Za-z0-9_]*", joint)
                         else "joint_controller")
        p = declare(self, PARAMS)
        if p["effort_subscribers"] < 1 or p["match_timeout_s"] <= 0:
            raise ParameterError("effort_subscribers must be >= 1 and match_timeout_s > 0 s")
        try:
            check_priority(p["rt_priority"])
        except ValueError as exc:
            raise ParameterError(f"parameter {exc}") from None
        check_choice("controller", p["controller"], CONTROLLER_KINDS)
        if not p["joint"]:   # a params file's /NS/joint_controller_J section had not reached the node it names
            raise ParameterError("parameter joint: not given: -p joint:=J (the node is joint_controller_J only once "
                                 "it has J from the command line or -r __node:=joint_controller_J, so a params file's "
                                 "section of that node reaches it only then)")
        # every setting it runs: read-only parameters, this joint's values (the launcher's params file, else the
        # config's), and its arm read once from arm_file (ros/settings_params.py: JOINT_CONTROLLER_KEYS)
        settings, index = declare_joint_settings(self, p["controller"], p["joint"], p["config_file"])
        arm = settings.arm
        self.p = p
        self.joint = p["joint"]
        self.clock_ = StepClock(settings.simulation.dt_s)
        # a bank of this one joint behind its state guard, as the in-process simulation runs all the arm's
        self.loop_ = JointLoop(build_guarded_controllers(settings, p["controller"], [index]),
                               settings.reference.preview_steps)
        controller = self.loop_.controller
        print(f"CONTROLLER joint_controller {p['joint']}: {type(controller).__name__}", flush=True)
        self.checkpoint = Path(p["checkpoint_file"]) if p["checkpoint_file"] else None
        if self.checkpoint is not None and not controller.learns:
            raise ParameterError(f"checkpoint_file: the {p['controller']} controller has no learned state to save")
        # a controller that learns nothing runs no checkpoint settings
        self.checkpoint_every = (max(1, int(round(settings.checkpoint.period_s / settings.simulation.dt_s)))
                                 if controller.learns else 1)
        self.checkpoint_phase = checkpoint_phase(index, arm.n_joints, self.checkpoint_every)
        self.resumed_from = None
        if p["init_file"] and not (p["resume"] and self.checkpoint is not None and self.checkpoint.is_file()):
            # a warm start from an earlier run: its weights and covariances, this run's own step count
            try:
                controller.load_state_dict(0, load_checkpoint(Path(p["init_file"]))[0], resume_steps=False)
            except (ValueError, KeyError, AttributeError) as exc:
                raise ParameterError(f"init_file: {exc}") from None
            print(f"WARM joint_controller {self.joint} from {p['init_file']}", flush=True)
        if p["resume"] and self.checkpoint is not None and self.checkpoint.is_file():
            try:
                state, step = load_checkpoint(self.checkpoint)
                controller.load_state_dict(0, state)
            except (ValueError, KeyError) as exc:
                raise ParameterError(f"resume: {exc}") from None
            self.resumed_from = step
            print(f"RESUMED joint_controller {self.joint} from the checkpoint of step {step}", flush=True)
        kill_s = settings.faults.kill_controller_at_s[index]
        # the injected crash hits the first incarnation only (a restarted controller is not killed again)
        self.kill_step = (int(round(kill_s / settings.simulation.dt_s)) if kill_s >= 0 and p["incarnation"] == 0
                          else None)
        self.malformed = 0
        self.states_received = 0
        self.efforts_sent = 0
        self._state_layout = joint_state_cdr.OneJointLayout(self.joint, ("position", "velocity"))
        self._effort_layout = joint_state_cdr.OneJointLayout(self.joint, ("effort",))
        qos = loop_qos(p["reliability"], depth=p["queue_depth"])
        self.torque_limit = settings.plant.torque_limit_nm[index]
        # The effort topic is offered only once the first reference batch is in: the plant starts when
        # every effort topic has its publisher, so its state 0 never waits on a reference still in discovery.
        self._pub = None
        self._link = None
        self._effort_setup = (settings.faults, index, qos)
        self._held: list[tuple[int, float]] = []  # (step, torque N m) answers waiting for the subscribers
        self._matched = False
        self.held_answers = 0
        self._state_sub = self.create_subscription(JointState, state_topic(self.joint), self._on_state, qos,
                                                   raw=True)
        self.malformed_references = 0
        # raw: the batch is read straight from CDR (wire/trajectory_cdr.py), no rclpy message per point
        self.create_subscription(JointTrajectory, reference_topic(self.joint), self._on_reference, reference_qos(),
                                 raw=True)
        self.diagnostics = DiagnosticsReporter(self, lambda: [self._status()],
                                               lambda: self.clock_.stamp(max(0, self.loop_.last_step)))
        self.cpu = CpuMeter()
        if p["sched_batch"]:  # before SCHED_FIFO: a granted --rt-priority replaces it
            print(apply_batch()[1], flush=True)
        self.rt_applied, rt_message = apply_fifo(p["rt_priority"])
        if p["rt_priority"]:
            print(rt_message, flush=True)
        announce_ready(f"joint_controller {self.joint}")
        announce_when_ready(self, self._ready_for_steps)

    def _ready_for_steps(self) -> str | None:
        """The start handshake (``ros/ready.py``): None once the state reader has matched the plant's writer, the
        references that state 0 needs are here and the effort publisher has its subscribers; else what is
        missing."""
        if self._state_sub.get_publisher_count() < 1:
            return f"its {self._state_sub.topic_name} reader has not matched the plant"
        if not self.loop_.holds_references_for(0):
            return "the references state 0 needs have not arrived"
        if not self._matched:
            return "; ".join(self._match.lacking) or "its effort publisher is not matched yet"
        return None

    def _on_state(self, data: bytes) -> None:
        try:
            sec, nanosec, (q, qd) = self._state_layout.decode(data)
        except (ValueError, IndexError, struct.error, UnicodeDecodeError):
            self.malformed += 1
            return
        self.states_received += 1
        step = self.clock_.step_of_sec_nanosec(sec, nanosec)
        self.cpu.mark(step)
        if self.kill_step is not None and step >= self.kill_step:
            print(f"KILLED joint_controller {self.joint} at step {step} (fault injection)", flush=True)
            os.kill(os.getpid(), signal.SIGKILL)
        self._publish(self.loop_.on_state(step, q, qd))
        self.loop_.learn()  # after the effort is out: the training is not on the state-to-effort path

    def _offer_effort(self) -> None:
        """Create the effort publisher (and its fault-injecting link, if configured)."""
        faults, index, qos = self._effort_setup
        self._pub = self.create_publisher(JointState, effort_topic(self.joint), qos)
        self._link = faulty_link(faults, "effort", index, self._pub.publish, self.torque_limit)
        self._match = MatchWait([Need(self._pub.topic_name, "subscribers", self.p["effort_subscribers"],
                                      self._pub.get_subscription_count)], self.p["match_timeout_s"])
        self._match_timer = wall_timer(self, 0.005, self._check_matched)
        print(f"OFFERED joint_controller {self.joint} {self._pub.topic_name}", flush=True)

    def _check_matched(self) -> None:
        """Release the held answers once every expected subscriber has matched the effort publisher."""
        status = self._match.poll()
        if status == "waiting":
            return
        if status == "timeout":
            self.get_logger().warning(f"{'; '.join(self._match.lacking)} after {self._match.waited_s:.1f} s; "
                                      "publishing anyway")
        self.destroy_timer(self._match_timer)
        self._matched = True
        held, self._held = self._held, []
        self._send(held)

    def _on_reference(self, data: bytes) -> None:
        try:
            sec, nanosec, positions, velocities = decode_first_joint(data)
        except (ValueError, IndexError, struct.error):
            self.malformed_references += 1
            return
        if self._pub is None:
            self._offer_effort()
        first = self.clock_.step_of_sec_nanosec(sec, nanosec)
        self._publish(self.loop_.add_reference(first, positions, velocities))
        self.loop_.learn()

    def _publish(self, answers) -> None:
        if answers and self._pub is None:  # a bad state answered before any reference came
            self._offer_effort()
        if self._matched:
            self._send(answers)
        else:
            self._held.extend(answers)
            self.held_answers += len(answers)

    def _send(self, answers) -> None:
        for step, effort in answers:
            sec, nanosec = self.clock_.sec_nanosec(step)
            if self._link is None:
                self._pub.publish(self._effort_layout.encode(sec, nanosec, effort))
            else:
                fate = self._link.fate()
                value = self._link.corrupt_value() if fate.corrupt else effort
                self._link.send(self._effort_layout.encode(sec, nanosec, value), fate)
            self.efforts_sent += 1
            if self.checkpoint is not None and checkpoint_due(step, self.checkpoint_every, self.checkpoint_phase):
                self._save_checkpoint()

    def _save_checkpoint(self) -> None:
        save_checkpoint(self.checkpoint, self.loop_.controller.state_dict(0), self.loop_.last_step)

    def counters(self) -> dict:
        loop = self.loop_
        c = loop.guarded.counters(0)   # the guard's and the controller's (EKF resets), as in-process runs report
        c.update({"malformed_states": self.malformed, "malformed_references": self.malformed_references, "states": self.states_received, "efforts": self.efforts_sent,
                  "duplicate_states": loop.duplicates, "last_step": loop.last_step,
                  "held_until_matched": self.held_answers})
        if self._link is not None:
            c.update({f"injected_effort_{k}": v for k, v in self._link.counters().items()})
        return c

    def _status(self):
        return status(status_name(self, "joint_controller", self.joint), self.get_name(), self.counters(),
                      FAULT_KEYS)

    def close(self) -> None:
        self.loop_.learn()  # a training left pending by an interrupted callback
        if self._link is not None:
            self._link.close()
        if self.checkpoint is not None and self.loop_.last_step >= 0:
            self._save_checkpoint()
        counters = self.counters()
        counters["resumed_from_step"] = self.resumed_from
        counters["rt_priority_applied"] = self.rt_applied
        counters["sched_policy"] = policy_name()
        counters["cpu"] = self.cpu.report()
        if self.p["stats_file"]:
            write_json(self.p["stats_file"], counters)
        loop = self.loop_
        print(f"STATS joint_controller {self.joint}: " + ", ".join(f"{k} {v}" for k, v in counters.items())
              + f", waiting for references {len(loop.pending_steps)}, reference steps buffered "
              f"{loop.reference_span}", flush=True)
        print(self.cpu.line(self.get_name()), flush=True)


def main(args=None) -> NoReturn:
    exit_process(run_node(functools.partial(JointControllerNode, args), args, params=PARAMS))


if __name__ == "__main__":
    main()

"""A small lockstep robot for the joint bus's fault tests (run as its own process).

    python test/robot_probe.py DOMAIN_ID FAULT STEP [ARM]

Speaks the standard interface (docs/your_robot.md) without physics and without /clock: publishes the arm's
JointState on /robot_joint_states (the arm's joints in reverse order, so matching by name is exercised; the
configured initial posture, velocity 0; stamped with a wall-clock-like time that does not start at 0), waits
for the JointState command stamped with it, then publishes the next state; re-sends a state every 0.25 s
until its command comes. From step STEP on it injects FAULT: ``stop`` (publishes nothing more),
``missing`` (leaves joint index 2 of the arm out of the names), ``nan`` (position of the arm's second joint is
NaN), ``dup`` (names the arm's first joint a second time, last, at 5 rad), ``beyond`` (the arm's first joint
0.2 rad beyond its upper limit: past the joint controllers' guard margin), ``rival`` (a second publisher on the
command topic from the start: another commander; it sends nothing), ``twin`` (a second publisher on the state
topic from the start: another robot; it sends nothing), ``frozen`` (every state from STEP on stamped
as state STEP), ``back`` (the stamps restart from the first one's at STEP: a restarted simulation), ``skip`` (the
stamps from STEP on one step later: 2 steps after the previous one), ``nowait`` (from STEP on, states without
waiting for commands: STEP + 1's right behind STEP's, then every 1 ms of wall time), ``none`` (no fault). Prints
``COMMAND <step> <stamp ns> <efforts>`` for every command it takes and ends on SIGINT or SIGTERM with ``PROBE END``.
"""
import os
import signal
import sys
import time


def main() -> int:
    os.environ["ROS_DOMAIN_ID"] = sys.argv[1]
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    fault, fault_step = sys.argv[2], int(sys.argv[3])
    arm_name = sys.argv[4] if len(sys.argv) > 4 else "pa10"
    import rclpy
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import JointState

    from pa10_dnbs.config import default_config_path
    from pa10_dnbs.plant.from_config import initial_state
    from pa10_dnbs.run_settings import build_settings

    cfg = build_settings(default_config_path(), arm=arm_name)
    names = list(cfg.arm.joint_names)
    q0, _ = initial_state(cfg.simulation, cfg.reference)
    rclpy.init(signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
    node = rclpy.create_node("robot_probe")
    qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
    pub = node.create_publisher(JointState, "/robot_joint_states", qos)
    commands = []
    node.create_subscription(JointState, "/robot_joint_command", commands.append, qos)
    if fault == "rival":
        rival = node.create_publisher(JointState, "/robot_joint_command", qos)  # noqa: F841 - kept for the run
    if fault == "twin":
        twin = node.create_publisher(JointState, "/robot_joint_states", qos)  # noqa: F841 - kept for the run
    stop = []
    signal.signal(signal.SIGINT, lambda *_: stop.append(1))
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    t0_ns, dt_ns = 1_700_000_000 * 10**9, 1_000_000  # not 0: the bus counts the graph's time from the first state
    k = 0
    print("PROBE READY", flush=True)
    while not stop:
        step = {"frozen": min(k, fault_step), "back": k - fault_step if k >= fault_step else k,
                "skip": k + 1 if k >= fault_step else k}.get(fault, k)
        stamp = t0_ns + step * dt_ns
        msg = JointState()
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp, 10**9)
        order = list(reversed(range(len(names))))
        if fault == "missing" and k >= fault_step:
            order.remove(2)
        pos = [float(q0[i]) for i in order]
        if fault == "nan" and k >= fault_step:
            pos[order.index(1)] = float("nan")
        if fault == "beyond" and k >= fault_step:
            pos[order.index(0)] = float(cfg.arm.upper_rad[0]) + 0.2
        msg.name, msg.position, msg.velocity = [names[i] for i in order], pos, [0.0] * len(order)
        if fault == "dup" and k >= fault_step:
            msg.name, msg.position, msg.velocity = msg.name + [names[0]], pos + [5.0], [0.0] * (len(order) + 1)
        silent = fault == "stop" and k >= fault_step
        if fault == "nowait" and k == fault_step > 0:
            ahead = JointState()
            ahead.header.stamp.sec, ahead.header.stamp.nanosec = divmod(stamp + dt_ns, 10**9)
            ahead.name, ahead.position, ahead.velocity = msg.name, msg.position, msg.velocity
        answered = False
        next_send = 0.0
        while not stop and not answered:
            if not silent and time.monotonic() >= next_send:
                pub.publish(msg)
                next_send = time.monotonic() + 0.25
                if fault == "nowait" and k == fault_step > 0:   # the next state right behind it, built beforehand:
                    pub.publish(ahead)                           # in lockstep always before the command answering it
                    k += 1
            nowait = fault == "nowait" and k >= fault_step
            rclpy.spin_once(node, timeout_sec=0.0 if nowait else 0.02)
            while commands:
                c = commands.pop(0)
                c_ns = c.header.stamp.sec * 10**9 + c.header.stamp.nanosec
                print(f"COMMAND {(c_ns - t0_ns) // dt_ns} {c_ns} {list(c.effort)}", flush=True)
                answered = answered or c_ns == stamp
            if nowait:
                time.sleep(0.001)
                answered = True
        k += 1
    print("PROBE END", flush=True)
    sys.stdout.flush()
    os._exit(0)


if __name__ == "__main__":
    sys.exit(main())

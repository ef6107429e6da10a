"""Every node's bad parameter: exit code 2 and one line on stderr naming it, before the node does anything.

Each case runs the node's main in its own process (rclpy starts, on the test's own domain); the cases run
in parallel to keep the fast tier fast.
"""
import subprocess
import sys
import time

from graph_harness import REPO, ros_env

CASES = [  # (node module, bad parameter, word the error line must hold): each node, and each kind of check
    ("plant.node", "deadline_fraction:=2.0", "deadline_fraction"),      # outside the descriptor's range
    ("joint_controller_node", "queue_depth:=many", "queue_depth"),      # wrong type
    ("reference_node", "config_file:=/no/such/config.yaml", "config_file"),
    ("wire_monitor", "poll_period_s:=0.5", "out_file"),                 # a required parameter missing
    ("recorder_node", "qos_depth:=0", "qos_depth"),
    ("live_observer_node", "port:=70000", "port"),
    ("plant.node", "on_missing_effort:=guess", "on_missing_effort"),  # not one of the choices
    ("plant.node", "interface:=ros2_control", "interface"),
    ("joint_bus_node", "robot_command:=torque", "robot_command"),     # before it waits for any robot
    ("joint_bus_node", "robot_timeout_s:=0.0", "robot_timeout_s"),
    ("plant.node", "simulation.dt_s:=0.5", "simulation.dt_s"),                  # a setting: outside its range
    ("plant.node", "plant.torque_limit_nm:=[1.0,2.0]", "plant.torque_limit_nm"),  # not one value per joint
    ("reference_node", "arm_file:=/no/such/arm.yaml", "arm_file"),
    # a joint controller's setting: its joint's one value (a strict bound; a list where one double is its value)
    ("joint_controller_node", ("joint:=s1", "dnbs.alpha_net.error_scale_rad:=0.0"), "dnbs.alpha_net.error_scale_rad"),
    ("joint_controller_node", ("joint:=s1", "controller:=pid", "pid.kp:=[1.0,2.0]"), "pid.kp"),
    # rev_e 15: a value rcl itself cannot read (it failed rclpy.init: an RCLError traceback, exit 1)
    ("joint_bus_node", "robot_command:=forward:", "robot_command"),
    ("plant.node", "duration_s:=[1,", "duration_s"),
    # rev_e 16: the plant as a robot reading its own states as commands
    ("plant.node", ("interface:=standard", "robot_state_topic:=/a", "robot_command_topic:=/a"), "robot_command_topic"),
    # a node started by hand (docs/graph.md), each was a traceback and exit 1, or a run that failed at its end:
    ("reference_node", "__ns:=/pa10/", "namespace must not end with a '/'"),   # "node name must not start with ..."
    ("reference_node", "use_sim_time:=maybe", "use_sim_time"),                  # rclpy's own parameter
    ("joint_controller_node", ("joint:=s1", "queue_depth:=4294967297"), "queue_depth"),   # a QoS TypeError
    ("reference_node", "batch_steps:=1000000000", "batch_steps"),               # 52 GiB asked at the start
    ("reference_node", "stats_file:=/no/such/dir/r.json", "stats_file"),        # written only at the end
    ("joint_controller_node", ("joint:=s1", "checkpoint_file:=/no/such/dir/c.npz"), "checkpoint_file"),
    ("wire_monitor", "out_file:=/no/such/dir/w.npz", "out_file"),
    ("recorder_node", ("bag:=/no/such/dir/b", "all_topics:=true"), "bag"),
    ("plant.node", ("interface:=standard", "robot_state_topic:=bad name"), "robot_state_topic"),
    ("mujoco_robot_node", "command_topic:=/a//b", "command_topic"),
    ("joint_controller_node", "controller:=pid", "joint: not given"),           # was "must be one of ..., got ''"
]


def _ros_args(param) -> list[str]:
    """``-p`` each rule, ``-r`` a remapping of the node's name or namespace."""
    return [a for one in (param if isinstance(param, tuple) else (param,))
            for a in ("-r" if one.startswith(("__ns:=", "__node:=")) else "-p", one)]
TIMEOUT_S = 60


def test_bad_parameter_exits_2_with_one_line(domain):
    procs = [subprocess.Popen(["timeout", "-k", "5", str(TIMEOUT_S), sys.executable, "-m", f"pa10_dnbs.ros.{module}",
                               "--ros-args", *_ros_args(param)], cwd=REPO, env=ros_env(domain), text=True,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE)
             for module, param, _ in CASES]
    results = [p.communicate(timeout=TIMEOUT_S + 10) for p in procs]
    for (module, param, word), p, (out, err) in zip(CASES, procs, results):
        lines = [ln for ln in err.splitlines() if ln.strip()]
        assert p.returncode == 2, (module, param, p.returncode, out, err)
        assert len(lines) == 1 and word in lines[0] and "Traceback" not in err, (module, param, err)


def test_a_half_built_node_is_freed_only_under_the_exit_deadline(domain):
    """A node whose constructor fails frees its half-built node (and with it the DDS participant and its
    shared-memory files) only once the teardown's exit deadline is armed: destroying the handle can spin
    forever with the GIL held (a plant that rejected a parameter once spun for 10 min, SIGTERM ignored)."""
    import json

    from pa10_dnbs.ros.shm_cleanup import shm_files, unused

    before = shm_files()
    p = subprocess.run(["timeout", "-k", "5", str(TIMEOUT_S), sys.executable,
                        str(REPO / "test" / "failed_start_probe.py"), str(domain)],
                       cwd=REPO, env=ros_env(domain), text=True, capture_output=True, timeout=TIMEOUT_S + 10)
    assert p.returncode == 0, p.stderr
    assert "FAILED parameter probe: rejected on purpose" in p.stderr
    assert json.loads(p.stdout.strip().splitlines()[-1]) == {"code": 2, "events": ["armed", "freed"]}
    # LTTng-UST's lttng-ust-wait-* files are made by loading rclpy at all, in the first ROS process on a clean
    # /dev/shm, never by a participant (the launcher removes them, shm_cleanup.py): only Fast DDS's count here,
    # and only those still there once a concurrent run's launcher has had time to clean up after its own nodes
    deadline = time.monotonic() + 20.0
    while ((leaked := {f for f in unused(shm_files() - before) if not f.startswith("lttng-ust-wait-")})
           and time.monotonic() < deadline):
        time.sleep(0.5)
    assert not leaked, f"shared-memory files left behind: {sorted(leaked)}"


def test_a_wrong_type_in_a_complete_params_file_is_one_line_naming_the_key(cfg, tmp_path, domain):
    """With every setting in the params file its values are the declared defaults: one of the wrong type for a
    ranged key (a string for plant.payload_kg) is refused in one line, exit 2, not a traceback."""
    from pa10_dnbs.supervisor.params_file import write_params_file

    params = write_params_file(tmp_path / "ros_params.yaml", cfg, "pid", "/pa10")
    text = params.read_text()
    assert "payload_kg: 0.0" in text
    params.write_text(text.replace("payload_kg: 0.0", "payload_kg: 'heavy'", 1))
    p = subprocess.run(["timeout", "-k", "5", str(TIMEOUT_S), sys.executable, "-m", "pa10_dnbs.ros.plant.node",
                        "--ros-args", "-r", "__ns:=/pa10", "--params-file", str(params)],
                       cwd=REPO, env=ros_env(domain), text=True, capture_output=True, timeout=TIMEOUT_S + 10)
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert p.returncode == 2 and len(lines) == 1 and "plant.payload_kg" in lines[0], p.stderr
    assert "Traceback" not in p.stderr


def test_an_unknown_ros_argument_is_one_line(domain):
    """rclpy.init refuses it (UnknownROSArgsError, after rcl's own log line): one line, exit 2, not a traceback."""
    p = subprocess.run(["timeout", "-k", "5", str(TIMEOUT_S), sys.executable, "-m", "pa10_dnbs.ros.joint_bus_node",
                        "--ros-args", "--bogus"], cwd=REPO, env=ros_env(domain), text=True, capture_output=True,
                       timeout=TIMEOUT_S + 10)
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert p.returncode == 2 and lines == ["FAILED unknown ROS arguments ['--bogus']"], (p.returncode, p.stderr)

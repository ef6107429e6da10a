"""The numeric core imports only numpy (and the standard library); the launcher imports no rclpy; the CLI loads
no plotting or bag library before a command needs it."""
import subprocess
import sys

CODE = """
import sys
import pa10_dnbs.core.reference, pa10_dnbs.core.honn, pa10_dnbs.core.ekf
import pa10_dnbs.core.dnbs_controller, pa10_dnbs.core.pid_controller, pa10_dnbs.core.metrics
import pa10_dnbs.core.joint_trajectory, pa10_dnbs.core.trajectory_reference
bad = sorted(m for m in sys.modules if m.split('.')[0] in
             ('rclpy', 'pybullet', 'pybullet_utils', 'yaml', 'matplotlib', 'scipy', 'torch'))
print(','.join(bad))
"""


def test_core_pulls_in_no_ros_no_pybullet():
    out = subprocess.run([sys.executable, "-c", CODE], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "", f"core imported: {out.stdout.strip()}"


LAUNCHER = """
import sys
import pa10_dnbs.cli, pa10_dnbs.commands.launch
print(','.join(sorted(m for m in sys.modules if m.split('.')[0] in ('rclpy', 'rosidl_runtime_py'))))
"""


def test_launcher_does_not_load_rclpy():
    """The launcher only supervises: it never joins DDS, so it loads no rcl (nor rcl's LTTng-UST,
    whose /dev/shm files it could not then clean up while it still maps them)."""
    out = subprocess.run([sys.executable, "-c", LAUNCHER], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "", f"the launcher imported: {out.stdout.strip()}"


CHECKS_ONLY = """
import sys
import pa10_dnbs.cli, pa10_dnbs.commands.simulate, pa10_dnbs.commands.study, pa10_dnbs.commands.tune
print(','.join(sorted({m.split('.')[0] for m in sys.modules} & {'matplotlib', 'rosbags', 'optuna', 'dask'})))
"""

NO_FIGURES = """
import sys
from pa10_dnbs.cli import main
code = main(['simulate', '--duration', '0.05', '--no-figures', '--out', sys.argv[1]])
print(code, 'matplotlib' in sys.modules)
"""


def test_the_cli_and_a_commands_checks_load_no_plotting_no_bags():
    """The CLI, and what simulate, study and tune import before they run (their input checks), load neither
    matplotlib nor rosbags (about 0.3 s), nor Optuna or Dask: ``--help`` and a refused input answer at once, and
    the test tiers' hundreds of such calls stay cheap. The errors the CLI ends on derive from refused.Refused, so
    it need not import their modules."""
    out = subprocess.run([sys.executable, "-c", CHECKS_ONLY], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "", f"imported before any run: {out.stdout.strip()}"


def test_a_run_without_figures_never_loads_matplotlib(tmp_path):
    out = subprocess.run([sys.executable, "-c", NO_FIGURES, str(tmp_path / "out")], capture_output=True, text=True,
                         check=True)
    assert out.stdout.splitlines()[-1] == "0 False", out.stdout + out.stderr
    assert (tmp_path / "out" / "metrics.json").is_file() and not list((tmp_path / "out").glob("*.png"))


# Layers from the ground up: a module may import its own layer and the ones below, never one above.
LAYERS = [
    {"__init__", "paths", "atomic_file", "run_data", "core", "wire", "kinematics", "faults",  # numpy-only data and maths
     "config_error", "refused", "interrupt", "cli_values", "output_lock", "output_mark", "number_text", "run_size",
     "run_steps", "json_text", "file_path", "console_stream", "setting_flags", "source_digest"},
    {"arm", "config", "config_yaml"},                                          # an arm's files; a config file
    {"settings"},                                                              # a run's typed settings
    {"plant", "loop", "accel", "trajectory_file"},                             # physics, loop logic, compiled step
    {"derived_settings", "run_settings"},                                      # the rules; settings built once
    {"controller_factory"},                                                   # what a joint runs
    {"sim", "bag", "report", "live"},                                          # in-process runs, bags, outputs, live view
    {"study", "tune"},                                                         # robustness study, tuning: sim runs
    {"ros"},                                                                   # the nodes (rclpy)
    {"supervisor"},                                                            # starts and watches the nodes
    {"commands"},
    {"cli"},
]
ROS_PACKAGES = {"rclpy", "rosidl_runtime_py", "builtin_interfaces", "std_msgs", "sensor_msgs", "trajectory_msgs",
                "rosgraph_msgs", "diagnostic_msgs", "tf2_msgs", "rcl_interfaces"}


def _imports():
    """(unit, imported pa10_dnbs unit or None, top-level external package or None, file) for every import."""
    import ast
    from pathlib import Path

    root = Path(__file__).resolve().parent.parent / "pa10_dnbs"
    for path in sorted(root.rglob("*.py")):
        rel = path.relative_to(root.parent).with_suffix("").parts
        unit = rel[1] if len(rel) > 1 else "__init__"
        pkg = rel[:-1]
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom):
                target = (list(pkg[:len(pkg) - node.level + 1]) + (node.module.split(".") if node.module else [])
                          if node.level else (node.module or "").split("."))
                targets = [target]
            elif isinstance(node, ast.Import):
                targets = [a.name.split(".") for a in node.names]
            else:
                continue
            for t in targets:
                if t[0] == "pa10_dnbs":
                    yield unit, (t[1] if len(t) > 1 else "__init__"), None, path.name
                else:
                    yield unit, None, t[0], path.name


def test_no_layer_imports_a_higher_one():
    rank = {u: i for i, layer in enumerate(LAYERS) for u in layer}
    wrong = [f"{unit}/{f} imports {dep}" for unit, dep, _, f in _imports()
             if dep is not None and rank[dep] > rank[unit]]
    assert not wrong, "imports that run up the layers: " + "; ".join(sorted(set(wrong)))


def test_only_ros_imports_ros():
    """Everything but ros/ runs without a ROS install (bags are read and written with rosbags, not rclpy)."""
    wrong = [f"{unit}/{f} imports {ext}" for unit, _, ext, f in _imports() if ext in ROS_PACKAGES and unit != "ros"]
    assert not wrong, "; ".join(sorted(set(wrong)))

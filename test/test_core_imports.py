"""The numeric core imports only numpy (and the standard library); the launcher imports no rclpy."""
import subprocess
import sys

CODE = """
import sys
import pa10_dnbs.core.reference, pa10_dnbs.core.honn, pa10_dnbs.core.ekf
import pa10_dnbs.core.dnbs_controller, pa10_dnbs.core.pid_controller, pa10_dnbs.core.metrics
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

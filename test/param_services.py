"""One call to a running node's parameter service (rcl_interfaces), as a ROS user's tool makes it: the probes'
shared client (gain_probe.py, settings_probe.py)."""
import rclpy


def call(node, kind, service: str, request):
    """The answer of ``service`` (type ``kind``) to ``request``; SystemExit naming the service after 30 s."""
    client = node.create_client(kind, service)
    if not client.wait_for_service(timeout_sec=30.0):
        raise SystemExit(f"no service {service}")
    future = client.call_async(request)
    rclpy.spin_until_future_complete(node, future, timeout_sec=30.0)
    if future.result() is None:
        raise SystemExit(f"no answer from {service}")
    return future.result()

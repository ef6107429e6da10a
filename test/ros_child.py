"""What the stand-in ROS processes of the tests share (rival_publisher.py, trajectory_listener.py): rclpy on a
test's domain, local discovery, no signal handlers of its own; a READY line, a loop until SIGINT or SIGTERM, an END
line and an exit that skips rclpy's teardown."""
import os
import signal


def ros_node(domain_id: str, name: str):
    """(rclpy, a node named ``name``) on ROS_DOMAIN_ID ``domain_id``, discovery on this host only."""
    os.environ["ROS_DOMAIN_ID"] = domain_id
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    import rclpy

    rclpy.init(signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
    return rclpy, rclpy.create_node(name)


def serve(ready: str, end: str, step) -> None:
    """Print ``ready``, call ``step()`` until SIGINT or SIGTERM, print ``end`` and exit 0 at once."""
    stop = []
    signal.signal(signal.SIGINT, lambda *_: stop.append(1))
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    print(ready, flush=True)
    while not stop:
        step()
    print(end, flush=True)
    os._exit(0)

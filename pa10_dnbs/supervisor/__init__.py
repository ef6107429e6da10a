"""The process supervisor of the node graph: it starts every node as a plain subprocess (not ROS launch), leases
its domain id, writes its params file, watches, restarts and stops the nodes, and cleans up after them.
``pa10-dnbs launch`` (commands/launch.py) drives it."""

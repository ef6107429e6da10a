"""Starting, watching and stopping the node graph (no launch package: plain subprocesses)."""

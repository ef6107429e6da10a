"""Fault injection on the wire: what a lossy, late or corrupting link does to one joint's messages."""

"""Implementations of the ``pa10-dnbs`` sub-commands."""

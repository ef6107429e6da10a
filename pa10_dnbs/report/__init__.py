"""Metrics files, figures and the Markdown report of a run."""

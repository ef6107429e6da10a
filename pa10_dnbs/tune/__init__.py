"""Tuning a controller on an arm with Optuna: search spaces, the objective, the search, the report (docs/tuning.md)."""

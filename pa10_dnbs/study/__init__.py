"""The robustness study: named scenarios, every (scenario, controller, seed) run in worker processes, tables."""

"""Keys of the run description the recorder stores in a bag's metadata ``custom_data``.

``pa10_dnbs.config`` holds the run's validated config as JSON; other
``pa10_dnbs.<key>`` entries hold launcher facts (controller, mode, duration_s, ...).
"""
CUSTOM_PREFIX = "pa10_dnbs."
CUSTOM_CONFIG = CUSTOM_PREFIX + "config"

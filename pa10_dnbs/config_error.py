"""The one error type of bad input (config files, arm files, flags): its message names the key or file."""


class ConfigError(ValueError):
    """A configuration value is missing, unknown, or invalid; the message names the key."""

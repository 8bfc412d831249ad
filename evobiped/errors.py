"""Errors a user can cause (bad config, genome, argument, model).

The CLI turns a :class:`UserError` into one line on stderr and exit status 2.
"""


class UserError(Exception):
    """Bad input from the user: reported as one line, exit status 2."""


class ConfigError(UserError):
    """A configuration value is missing, of the wrong type or out of range."""


class GenomeError(UserError):
    """A genome does not fit its controller's layout (length, NaN, range)."""

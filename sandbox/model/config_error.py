""":class:`ConfigError`, the one error for settings a user gave that are not acceptable: raised by
:mod:`sandbox.model.config` (ranges, files) and :mod:`sandbox.model.budget` (memory), so it sits below
both; ``sandbox.model.config`` is where callers import it from."""


class ConfigError(ValueError):
    """A configuration value or file a user gave is not acceptable."""

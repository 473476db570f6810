"""The one error of a deployment or scenario file that cannot be used."""

from __future__ import annotations


class ConfigError(ValueError):
    """An invalid configuration; the message names the offending key."""

    def __init__(self, key: str, reason: str) -> None:
        super().__init__(f"config key '{key}': {reason}")
        self.key = key

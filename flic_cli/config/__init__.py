"""Configuration: the typed components' defaults, the presets in ``flic_cli/configs/`` and the
user's ``--config`` file, validated once at load."""

from flic_cli.config.parser import (
    GROUND_REMOVERS,
    build_method,
    default_config,
    load_config,
    method_ground,
)

__all__ = ["GROUND_REMOVERS", "build_method", "default_config", "load_config", "method_ground"]

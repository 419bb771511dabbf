"""Configuration, validated once at load into typed objects.

- :mod:`flic_cli.config.component` -- what a configurable component is (methods, ground removers,
  the projection): a frozen, validated dataclass holding its parameters' single defaults;
- :mod:`flic_cli.config.schema` -- :class:`Config` and :class:`MethodSpec`, what runs work with;
- :mod:`flic_cli.config.parser` -- reading the presets (``configs/default.toml``) and the user's
  ``--config`` file into a :class:`Config`.
"""

from flic_cli.config.parser import defaults_path, load_config, parse_config
from flic_cli.config.schema import Config, MethodSpec

__all__ = ["Config", "MethodSpec", "defaults_path", "load_config", "parse_config"]

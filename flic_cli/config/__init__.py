"""Configuration, validated once at load into typed objects (what a configurable component is
lives in :mod:`flic_cli.component`, apart, so that components do not import the parser).

- :mod:`flic_cli.config.schema` -- :class:`Config` and :class:`MethodSpec`, what runs work with;
- :mod:`flic_cli.config.parser` -- reading the presets (``presets/default.toml``, shipped with the
  package; ``configs/`` in the repository links to that folder) and the user's ``--config`` file
  into a :class:`Config`.
"""

from flic_cli.config.parser import defaults_path, load_config, parse_config
from flic_cli.config.schema import Config, MethodSpec

__all__ = ["Config", "MethodSpec", "defaults_path", "load_config", "parse_config"]

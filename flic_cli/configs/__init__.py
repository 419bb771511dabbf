"""Documented defaults and Map Connection presets (TOML), shipped as ``flic_cli.configs``."""

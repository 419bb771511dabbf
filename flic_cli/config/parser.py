"""Configuration: the documented defaults in ``configs/default.toml``, overridden by --config."""

from __future__ import annotations

import copy
import sys
from importlib import resources
from pathlib import Path
from typing import Any

from flic_cli.errors import FlicInputError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

GROUND_REMOVERS = ("paper", "bogoslavskyi")


def _merge(base: dict, over: dict) -> dict:
    out = copy.deepcopy(base)
    for key, value in over.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = _merge(out[key], value)
        else:
            out[key] = value
    return out


def default_config() -> dict[str, Any]:
    """The defaults shipped in ``configs/default.toml``."""
    text = resources.files("flic_cli.configs").joinpath("default.toml").read_text("utf-8")
    return tomllib.loads(text)


def load_config(path: Path | None = None) -> dict[str, Any]:
    """Defaults, with the keys of the TOML file ``path`` (if given) laid over them."""
    cfg = default_config()
    if path is None:
        return cfg
    path = Path(path)
    if not path.is_file():
        raise FlicInputError(path, "config file does not exist")
    try:
        over = tomllib.loads(path.read_text("utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise FlicInputError(path, f"is not valid TOML ({exc})") from None
    return _merge(cfg, over)


def build_method(cfg: dict[str, Any], name: str, **override: Any) -> Any:
    """The method variant ``[methods.NAME]`` of the config, with keyword overrides.

    Returns an object following :class:`flic_cli.methods.base.Method`.
    """
    from flic_cli.methods import KINDS

    methods = cfg.get("methods", {})
    if name not in methods:
        raise FlicInputError(None, f"unknown method {name!r} (known: {', '.join(methods)})")
    params = {k: v for k, v in methods[name].items() if k not in ("kind", "ground")}
    params.update(override)
    kind = methods[name].get("kind")
    if kind not in KINDS:
        raise FlicInputError(None, f"method {name!r} has unknown kind {kind!r}")
    if "maps" in params:
        params["maps"] = tuple(tuple(m) for m in params["maps"])
    try:
        return KINDS[kind](**params)
    except (TypeError, ValueError) as exc:
        from flic_cli.config.component import describe

        raise FlicInputError(None, f"[methods.{name}] {describe(exc)}") from None


def method_ground(cfg: dict[str, Any], name: str) -> str:
    """The method's own ground remover (``ground`` key; ``"paper"`` when absent)."""
    g = cfg["methods"][name].get("ground", "paper")
    if g not in GROUND_REMOVERS:
        raise FlicInputError(None, f"method {name!r}: ground must be one of {GROUND_REMOVERS}")
    return g

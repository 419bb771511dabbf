"""Reading config files: the shipped presets (``flic_cli/config/presets/default.toml``), then the
user's ``--config`` file laid over them, validated once into a
:class:`flic_cli.config.schema.Config`.

Every problem -- a file that is not TOML, an unknown section or key, a value of the wrong type or
out of range -- is a :class:`flic_cli.errors.FlicInputError` naming the file, the table and key,
and the reason, e.g. ``my.toml: [methods.flic0] threshold_m: Input should be greater than 0 (got
-1.0)``.
"""

from __future__ import annotations

import copy
import sys
from importlib import resources
from pathlib import Path
from typing import Any

from flic_cli.component import describe
from flic_cli.config.schema import Config, MethodSpec
from flic_cli.errors import FlicInputError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

#: The top-level tables a config file may have.
SECTIONS = ("projection", "ground", "methods")

#: The top-level keys a config file may have besides its tables.
TOP_KEYS = ("default_methods", "default_semantic_methods")

#: Keys of a ``[methods.NAME]`` table besides the component's parameters.
METHOD_KEYS = ("kind", "ground", "like")


def defaults_path() -> Path:
    """The shipped presets, ``flic_cli/config/presets/default.toml`` (``configs/`` in the
    repository is a link to that folder)."""
    return Path(str(resources.files("flic_cli.config").joinpath("presets", "default.toml")))


def _read_toml(path: Path) -> dict[str, Any]:
    if path.is_dir():
        raise FlicInputError(path, "is a folder, expected a TOML config file")
    if not path.exists():
        raise FlicInputError(path, "config file does not exist")
    if not path.is_file():  # a FIFO or a device would block or never end
        raise FlicInputError(path, "is not a regular file, expected a TOML config file")
    try:
        return tomllib.loads(path.read_text("utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise FlicInputError(path, f"is not valid TOML ({exc})") from None
    except OSError as exc:
        raise FlicInputError(path, f"cannot be read ({exc.strerror})") from None


def _merge(base: dict[str, Any], over: dict[str, Any]) -> dict[str, Any]:
    out = copy.deepcopy(base)
    for key, value in over.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = _merge(out[key], value)
        else:
            out[key] = value
    return out


def load_config(path: Path | None = None) -> Config:
    """The shipped presets with the TOML file ``path`` (if given) laid over them, validated.

    Parameters
    ----------
    path : a user config file (same layout as ``configs/default.toml``; only the keys it sets
        change, and it may add method variants).

    Raises
    ------
    FlicInputError
        Naming the file and the offending table and key.
    """
    files = [defaults_path()]
    raw = _read_toml(files[0])
    if path is not None:
        files.append(Path(path))
        raw = _merge(raw, _read_toml(files[-1]))
    return parse_config(raw, tuple(files))


def parse_config(raw: dict[str, Any], files: tuple[Path, ...] = ()) -> Config:
    """Validate nested tables (as read from TOML) into a :class:`Config`.

    Errors name the last of ``files`` (the user's file when there is one).
    """
    from flic_cli.ground import REMOVERS
    from flic_cli.methods import KINDS

    where = files[-1] if files else None

    def fail(reason: str) -> FlicInputError:
        return FlicInputError(where, reason)

    unknown = [k for k in raw if k not in SECTIONS + TOP_KEYS]
    if unknown:
        what = f"section [{unknown[0]}]" if isinstance(raw[unknown[0]], dict) else unknown[0]
        raise fail(
            f"unknown {what} (known: {', '.join(f'[{s}]' for s in SECTIONS)}, "
            f"{', '.join(TOP_KEYS)})"
        )
    for section in SECTIONS:
        if section in raw and not isinstance(raw[section], dict):
            raise fail(f"[{section}] must be a table")

    from flic_cli.projection import Projection

    projection = _build(Projection, raw.get("projection", {}), "[projection]", fail)

    ground_tables = raw.get("ground", {})
    for name in ground_tables:
        if name not in REMOVERS:
            raise fail(f"unknown ground remover [ground.{name}] (known: {', '.join(REMOVERS)})")
    ground = {
        name: _build(cls, ground_tables.get(name, {}), f"[ground.{name}]", fail)
        for name, cls in REMOVERS.items()
    }

    method_tables = raw.get("methods", {})
    methods: dict[str, MethodSpec] = {}
    for name in method_tables:
        table = _resolve_like(method_tables, name, fail)
        kind = table.get("kind")
        if kind not in KINDS:
            raise fail(
                f"[methods.{name}] kind: {kind!r} is not a method kind (known: {', '.join(KINDS)})"
            )
        own = table.get("ground", "paper")
        if own not in REMOVERS:
            raise fail(
                f"[methods.{name}] ground: {own!r} is not a ground remover "
                f"(known: {', '.join(REMOVERS)})"
            )
        params = {k: v for k, v in table.items() if k not in METHOD_KEYS}
        method = _build(KINDS[kind], params, f"[methods.{name}]", fail)
        methods[name] = MethodSpec(name, kind, method, own, frozenset(params))

    default_methods = raw.get("default_methods", list(methods))
    if not isinstance(default_methods, list) or not all(
        isinstance(m, str) for m in default_methods
    ):
        raise fail("default_methods must be a list of method variant names")
    missing = [m for m in default_methods if m not in methods]
    if missing or not default_methods:
        raise fail(f"default_methods: no method variant {', '.join(missing) or '(empty list)'}")
    semantic_methods = raw.get("default_semantic_methods", [])
    if not isinstance(semantic_methods, list) or not all(
        isinstance(m, str) for m in semantic_methods
    ):
        raise fail("default_semantic_methods must be a list of method variant names")
    missing = [m for m in semantic_methods if m not in methods]
    if missing:
        raise fail(f"default_semantic_methods: no method variant {', '.join(missing)}")
    return Config(
        projection, ground, methods, tuple(default_methods), files, tuple(semantic_methods)
    )


def _resolve_like(
    tables: dict[str, Any], name: str, fail: Any, seen: tuple[str, ...] = ()
) -> dict[str, Any]:
    """The table of variant ``name`` with ``like = "OTHER"`` resolved (OTHER's keys first)."""
    table = tables[name]
    if not isinstance(table, dict):
        raise fail(f"[methods.{name}] must be a table")
    like = table.get("like")
    if like is None:
        return dict(table)
    if like in seen or like == name:
        raise fail(f"[methods.{name}] like: {like!r} refers back to itself")
    if like not in tables:
        raise fail(f"[methods.{name}] like: no method variant {like!r}")
    base = _resolve_like(tables, like, fail, (*seen, name))
    return {**base, **{k: v for k, v in table.items() if k != "like"}}


def _build(cls: type, params: Any, where: str, fail: Any) -> Any:
    if not isinstance(params, dict):
        raise fail(f"{where} must be a table")
    try:
        return cls(**params)
    except (TypeError, ValueError) as exc:
        raise fail(f"{where} {describe(exc)}") from None

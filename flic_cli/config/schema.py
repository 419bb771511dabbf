"""The typed configuration a run works with, built once by :func:`flic_cli.config.load_config`.

Config files are TOML with three kinds of tables, each validated by a component class (whose
fields, bounds and defaults are the single source of truth):

- ``[projection]``: :class:`flic_cli.projection.Projection`;
- ``[ground.NAME]``: the parameters of ground remover NAME (:data:`flic_cli.ground.REMOVERS`);
- ``[methods.NAME]``: a method variant: ``kind`` (a key of :data:`flic_cli.methods.KINDS`), its
  component's parameters, ``ground`` (the variant's own remover, used by ``--ground-remover own``)
  and optionally ``like = "OTHER"`` (start from variant OTHER's table).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from flic_cli.errors import FlicInputError

if TYPE_CHECKING:  # the projection component itself imports flic_cli.component
    from flic_cli.projection import Projection


@dataclass(frozen=True)
class MethodSpec:
    """A method variant of the config.

    Attributes
    ----------
    name : the variant's name (``[methods.NAME]``).
    kind : the method kind (``"flic"``, ``"bogoslavskyi"``, ``"dbscan"``, ...).
    method : the built component (see :class:`flic_cli.methods.base.Method`).
    ground : the variant's own ground remover (a key of :data:`flic_cli.ground.REMOVERS`).
    given : the parameters a config file sets for the variant (``like`` included); the others
        are the component's defaults, which :mod:`flic_cli.sensor_params` may derive from the
        data's sensor.
    """

    name: str
    kind: str
    method: Any
    ground: str
    given: frozenset[str] = frozenset()

    def as_table(self) -> dict[str, Any]:
        """The variant as a complete config table (every parameter, defaults included)."""
        return {"kind": self.kind, **_fields(self.method), "ground": self.ground}


@dataclass(frozen=True)
class Config:
    """A validated configuration.

    Attributes
    ----------
    projection : how SemanticKITTI scans become range images.
    ground : every registered ground remover, built with its ``[ground.NAME]`` parameters.
    methods : the method variants by name, in the order the files define them.
    default_methods : the variants ``flic evaluate`` and ``flic benchmark`` run by default.
    files : the config files it was read from (the shipped defaults first).
    default_semantic_methods : the variants ``flic evaluate --semantics oracle`` runs by default
        besides ``default_methods`` (those that cluster per class).
    """

    projection: Projection
    ground: dict[str, Any]
    methods: dict[str, MethodSpec]
    default_methods: tuple[str, ...]
    files: tuple[Path, ...] = field(default=())
    default_semantic_methods: tuple[str, ...] = field(default=())

    def method(self, name: str) -> MethodSpec:
        """The variant ``name``; a one-line error naming the known variants otherwise."""
        if name not in self.methods:
            raise FlicInputError(
                None, f"unknown method {name!r} (known: {', '.join(self.methods)})"
            )
        return self.methods[name]

    def remover(self, name: str) -> Any:
        """The ground remover ``name``; a one-line error naming the known ones otherwise."""
        if name not in self.ground:
            raise FlicInputError(
                None, f"unknown ground remover {name!r} (known: {', '.join(self.ground)})"
            )
        return self.ground[name]

    def as_dict(self, methods: list[str] | None = None) -> dict[str, Any]:
        """The effective configuration as nested tables (every value, defaults included).

        Parameters
        ----------
        methods : only these variants (all when None).
        """
        names = list(self.methods) if methods is None else methods
        return {
            "default_methods": list(self.default_methods),
            "default_semantic_methods": list(self.default_semantic_methods),
            "projection": _fields(self.projection),
            "ground": {name: _fields(r) for name, r in self.ground.items()},
            "methods": {name: self.methods[name].as_table() for name in names},
        }


def _fields(component: Any) -> dict[str, Any]:
    """A component's parameters as plain TOML/JSON values (tuples become lists). A parameter
    whose value is None (unset: e.g. column's ``run_jump``, derived from the beam table) is left
    out, as TOML has no null and reading the table back gives it its default None again."""

    def plain(value: Any) -> Any:
        if isinstance(value, tuple | list):
            return [plain(v) for v in value]
        return value

    values = {f.name: getattr(component, f.name) for f in dataclasses.fields(component)}
    return {name: plain(value) for name, value in values.items() if value is not None}

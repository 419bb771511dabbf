"""What makes a class a configurable component (a method, a ground remover, ...).

A component is a frozen pydantic dataclass: its fields are exactly the parameters that a config
table sets, with their types, bounds and defaults (the one place a default is written), and it is
validated whenever it is built -- from a config file, from the Python API or by
``dataclasses.replace`` in a sweep -- so a bad value fails at once with the key and the reason.

Example
-------
>>> from typing import Annotated
>>> from pydantic import Field
>>> from pydantic.dataclasses import dataclass
>>> @dataclass(frozen=True, config=STRICT)
... class Blur:
...     sigma_px: Annotated[float, Field(gt=0, description="pixels")] = 1.0
>>> Blur(sigma_px=2)
Blur(sigma_px=2.0)
"""

from __future__ import annotations

from pydantic import ConfigDict

#: Configuration of every component dataclass: unknown keys are errors, values are validated on
#: ``dataclasses.replace`` too.
STRICT = ConfigDict(extra="forbid", revalidate_instances="always")

__all__ = ["STRICT", "check_installed"]


def check_installed(component: object) -> None:
    """Fail with the install hint when ``component`` needs an optional package that is missing.

    A component that needs an optional extra defines ``check_installed(self) -> None``; it is
    called when a run builds the component into its pipeline, not when a config is parsed, so
    the shipped config (which names every remover and preset) loads without the extras.

    Raises
    ------
    FlicInputError
        From the component's own check.
    """
    check = getattr(component, "check_installed", None)
    if check is not None:
        check()


def describe(exc: Exception) -> str:
    """One line from a validation error: ``key: reason; key: reason``.

    Parameters
    ----------
    exc : a :class:`pydantic.ValidationError` (other exceptions give ``str(exc)``).
    """
    from pydantic import ValidationError

    if not isinstance(exc, ValidationError):
        return str(exc)
    parts = []
    for err in exc.errors():
        key = ".".join(str(k) for k in err["loc"]) or "value"
        msg = err["msg"].removeprefix("Value error, ")
        if err["type"] == "unexpected_keyword_argument":
            parts.append(f"{key}: unknown key")
        elif "input" in err and not isinstance(err["input"], dict):
            parts.append(f"{key}: {msg} (got {err['input']!r})")
        else:
            parts.append(f"{key}: {msg}")
    return "; ".join(parts)

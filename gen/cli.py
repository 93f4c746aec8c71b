"""Hydra overrides (`key=value`) over a typed config, with one-line errors.

Shared by the command lines (`python -m gen`, `python -m train`): every problem with the input
becomes a `UserError` whose message is one line naming the option.
"""

from __future__ import annotations

from typing import Any

from hydra import compose, initialize
from hydra.core.config_store import ConfigStore
from hydra.errors import HydraException, OverrideParseException
from omegaconf import OmegaConf
from omegaconf.errors import OmegaConfBaseException


class UserError(Exception):
    """Bad input: the message is shown to the user as is."""


def compose_config(name: str, schema: type, argv: list[str]) -> Any:
    """`argv` overrides applied to the dataclass `schema` -> an instance of it."""
    ConfigStore.instance().store(name=name, node=schema)
    try:
        with initialize(version_base=None, config_path=None):
            cfg = compose(config_name=name, overrides=argv)
        return OmegaConf.to_object(cfg)
    except (HydraException, OmegaConfBaseException, ValueError, TypeError) as exc:
        raise UserError(_one_line(exc, schema)) from None


def _one_line(exc: BaseException, schema: type) -> str:
    text = str(exc).strip()
    if isinstance(exc, OverrideParseException):
        return f"cannot parse the option {exc.override!r}: write options as key=value"
    if "Could not override" in text or "not in struct" in text or f"not in '{schema.__name__}'" in text:
        key = text.split("'")[1] if "'" in text else text
        return f"unknown option {key!r}; options: {', '.join(schema.__dataclass_fields__)}"
    cause = exc.__cause__ or exc.__context__
    inner = cause if isinstance(cause, OmegaConfBaseException) else exc
    key = getattr(inner, "full_key", None)
    message = str(inner).strip().splitlines()[0] if str(inner).strip() else text.splitlines()[0]
    return f"{key}: {message}" if key else message


def usage(command: str, schema: type) -> str:
    fields = schema.__dataclass_fields__.values()
    return f"usage: {command} [key=value ...]\n\noptions (default):\n" + "\n".join(
        f"  {f.name}={f.default if not callable(f.default_factory) else f.default_factory()}" for f in fields
    )

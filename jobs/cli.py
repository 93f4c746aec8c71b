"""The one command-line layer: `key=value` options over a typed dataclass, for every entry point.

Each command (`python -m gen`, `gen.check`, `eval`, `train`, the benches...) declares its options
as a dataclass (a trailing `# comment` on a field is its help) and hands it with a function to
`main`, which gives them all the same behaviour:

* `--help` (or `-h`, `help`) prints the usage, the docstring's first paragraph and every option
  with its default and help, and exits 0;
* bad input — an unknown or malformed option, a wrong type, a missing required value, an empty
  `out=`, anything the command raises as `UserError` — prints one line `error: ...` and exits 2,
  before any work;
* a run that fails (`Failed`) prints one line and exits 1; Ctrl-C exits 130, and a SIGTERM (a
  job scheduler's, a session's end) stops it the same way, its `finally` blocks run (the stage
  wall times an experiment keeps, a partial run's files), exit 143.

Parsing is Hydra's override grammar (`key=value`, `a.b=value`, `'list=[x,y]'`), so values are
typed and checked by OmegaConf. A command may take one positional argument (e.g. the dataset
folder of `gen.check`), given plainly or as `name=value`.
"""

from __future__ import annotations

import dataclasses
import inspect
import re
import signal
import sys
import threading
import typing
from collections.abc import Callable
from typing import Any, TypeVar

from hydra import compose, initialize
from hydra.core.config_store import ConfigStore
from hydra.errors import HydraException, OverrideParseException
from omegaconf import OmegaConf
from omegaconf.errors import MissingMandatoryValue, OmegaConfBaseException

T = TypeVar("T")
HELP_FLAGS = ("-h", "--help", "help")


class UserError(Exception):
    """Bad input: the message is shown to the user as is (exit 2)."""


class Failed(Exception):
    """The input was fine but the run failed: the message is shown as is (exit 1)."""


def compose_config(name: str, schema: type[T], argv: list[str]) -> T:
    """`argv` overrides applied to the dataclass `schema` -> an instance of it. An option given
    twice is refused (Hydra would silently keep the last)."""
    seen: dict[str, str] = {}
    for arg in argv:
        key = arg.split("=", 1)[0].lstrip("+~")
        if "=" in arg and key in seen:
            raise UserError(f"option {key!r} is given twice ({_shown(seen[key])} and {_shown(arg)}); give it once")
        seen[key] = arg
    argv = [_listed(arg, _list_options(schema)) for arg in argv]
    ConfigStore.instance().store(name=name, node=schema)
    try:
        with initialize(version_base=None, config_path=None):
            cfg = compose(config_name=name, overrides=argv)
        options = OmegaConf.to_object(cfg)
    except (HydraException, OmegaConfBaseException, ValueError, TypeError) as exc:
        raise UserError(_one_line(exc, schema)) from None
    _refuse_empty_out(options, seen)
    return options


def _shown(arg: str) -> str:
    """An option as typed, quoted where it holds a line break or another unprintable character,
    so the message stays one line."""
    return arg if arg.isprintable() else repr(arg)


def _refuse_empty_out(options: object, given: dict[str, str]) -> None:
    """An `out=` given empty (as `--help` shows an option without a default) would be the path "", the
    current folder: refused, as a missing value is, rather than written there."""
    for key in given:
        if key != "out" and not key.endswith(".out"):
            continue
        value: Any = options
        for part in key.split("."):
            value = getattr(value, part, None)
        if isinstance(value, str) and not value.strip():
            raise UserError(f"{key}= is empty, which would mean the current folder: name one ({key}=<folder>) or drop the option")


def _list_options(schema: type) -> set[str]:
    """The options typed as lists (`List[str]`, `list[str] | None`, ...)."""
    hints = typing.get_type_hints(schema)
    return {
        name
        for name, hint in hints.items()
        if any(typing.get_origin(t) is list or t is list for t in (hint, *typing.get_args(hint)))
    }


def _listed(arg: str, lists: set[str]) -> str:
    """A list option given a bare value (`holdout=red`, `suites=all`, `holdout=red,blue`) as the list
    it means (`holdout=[red]`); `key=null` and bracketed lists as they are."""
    key, sep, value = arg.partition("=")
    if not sep or key not in lists or not value or value.startswith("[") or value == "null":
        return arg
    return f"{key}=[{value}]"


def _one_line(exc: BaseException, schema: type) -> str:
    text = str(exc).strip()
    if isinstance(exc, OverrideParseException):
        return f"cannot parse the option {exc.override!r}: write options as key=value"
    if text.startswith("Ambiguous value for argument"):  # Hydra reads `key=a,b` as a sweep
        return f"{text}: write a list as 'key=[a,b]'"
    if isinstance(exc, MissingMandatoryValue):
        return f"missing option {exc.full_key}=..."
    if "Could not override" in text or "not in struct" in text or f"not in '{schema.__name__}'" in text:
        key = text.split("'")[1] if "'" in text else text
        return f"unknown option {key!r}; options: {', '.join(f.name for f in dataclasses.fields(schema))}"
    cause = exc.__cause__ or exc.__context__
    inner = cause if isinstance(cause, OmegaConfBaseException) else exc
    if isinstance(inner, MissingMandatoryValue):
        return f"missing option {inner.full_key}=..."
    key = getattr(inner, "full_key", None)
    message = str(inner).strip().splitlines()[0] if str(inner).strip() else text.splitlines()[0]
    return f"{key}: {message}" if key else message


def _helps(schema: type) -> dict[str, str]:
    """Field name -> the trailing comment on its line in the class source."""
    try:
        source = inspect.getsource(schema)
    except (OSError, TypeError):
        return {}
    return {m[1]: m[2].strip() for m in re.finditer(r"^\s+(\w+)\s*:[^#\n]*#\s*(.*)$", source, re.M)}


def _options(schema: type, prefix: str = "") -> list[tuple[str, str]]:
    """(`name=default`, help) for every option, nested dataclasses flattened to `a.b`."""
    helps, rows = _helps(schema), []
    for f in dataclasses.fields(schema):
        if f.default is not dataclasses.MISSING:
            default: Any = f.default
        elif f.default_factory is not dataclasses.MISSING:
            default = f.default_factory()
        else:
            rows.append((f"{prefix}{f.name}=...", f"{helps.get(f.name, '')} (required)".strip()))
            continue
        if dataclasses.is_dataclass(default):
            rows += _options(type(default), f"{prefix}{f.name}.")
        else:
            shown = "" if default is None else str(default).lower() if isinstance(default, bool) else default
            rows.append((f"{prefix}{f.name}={shown}", helps.get(f.name, "")))
    return rows


def usage(command: str, schema: type, doc: str = "", positional: str | None = None) -> str:
    head = f"usage: {command}{f' <{positional}>' if positional else ''} [key=value ...]"
    summary = inspect.cleandoc(doc).split("\n\n")[0] if doc else ""
    rows = [(k, h) for k, h in _options(schema) if not (positional and k.split("=")[0] == positional)]
    width = max((len(k) for k, _ in rows), default=0)
    lines = [f"  {k:<{width}}  {h}".rstrip() for k, h in rows]
    options = "options (default):\n" + "\n".join(lines) if lines else ""
    return "\n\n".join(part for part in (head, summary, options) if part)


def parse(command: str, schema: type[T], argv: list[str], positional: str | None = None) -> T:
    """`argv` -> the options, or `UserError` naming the problem."""
    value = None
    if positional:
        plain = [a for a in argv if "=" not in a]
        if len(plain) > 1:
            raise UserError(f"one <{positional}> expected, got {len(plain)}: {' '.join(plain)}")
        value = plain[0] if plain else None
        argv = [a for a in argv if "=" in a]
    options = compose_config(schema.__name__, schema, argv)
    if positional:
        if value is not None:
            setattr(options, positional, value)
        if getattr(options, positional) in (None, ""):
            raise UserError(f"missing <{positional}>: {usage(command, schema, positional=positional).splitlines()[0]}")
    return options


def main(
    command: str,
    schema: type[T],
    run: Callable[[T], int | None],
    argv: list[str] | None = None,
    *,
    doc: str = "",
    positional: str | None = None,
) -> int:
    """Parse `argv` (default: sys.argv[1:]) into `schema` and call `run`; returns the exit code."""
    argv = sys.argv[1:] if argv is None else argv
    if any(a in HELP_FLAGS for a in argv):
        print(usage(command, schema, doc, positional))
        return 0
    main_thread = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGTERM, _terminated) if main_thread else None
    try:
        return int(run(parse(command, schema, argv, positional)) or 0)
    except UserError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except Failed as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt as exc:
        print(f"error: {str(exc) or 'interrupted'}", file=sys.stderr)  # a bare Ctrl-C has no message
        return 143 if isinstance(exc, Terminated) else 130
    finally:
        if main_thread:
            signal.signal(signal.SIGTERM, previous)


class Terminated(KeyboardInterrupt):
    """A SIGTERM, stopping the run as Ctrl-C does."""


def _terminated(signum: int, frame: object) -> None:
    raise Terminated("terminated (SIGTERM)")

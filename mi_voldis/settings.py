"""Settings as data: dataclasses whose fields carry their default, a comment and their valid range.

Fitting (:class:`mi_voldis.fit.config.FitConfig`) and every task (:mod:`mi_voldis.tasks.settings`)
declare their settings with :func:`setting`; :class:`Settings` validates them (type, range, choices,
shape) whenever one is made or changed, reads them from a JSON file and ``--set name=value``
overrides with errors that name the key and where the value came from, writes them back as JSON,
and lists them for ``--help``.
"""
import dataclasses
import json
import math
import types

# keys a run's config.json holds beside the settings (what was fitted, on what), skipped when read back
RECORD_KEYS = ("dataset", "task", "space_used")


def setting(default, help, *, low=None, high=None, above=None, choices=None, check=None):
    """A dataclass field with its ``help`` comment and its valid values: ``low`` <= v <= ``high``,
    ``above`` < v, v in ``choices``, and ``check(v)`` returning an error text (or None) for anything
    else (shapes of lists)."""
    meta = {"help": help, "low": low, "high": high, "above": above, "choices": choices, "check": check}
    if isinstance(default, (list, dict)):
        return dataclasses.field(default_factory=lambda: json.loads(json.dumps(default)), metadata=meta)
    return dataclasses.field(default=default, metadata=meta)


def _type_error(value, kind):
    """Why ``value`` is not of the annotated ``kind`` (None when it is)."""
    kinds = kind.__args__ if isinstance(kind, types.UnionType) else (kind,)
    for k in kinds:
        if k is type(None) and value is None:
            return None
        if k is bool and isinstance(value, bool):
            return None
        if k is int and isinstance(value, int) and not isinstance(value, bool):
            return None
        if k is float and isinstance(value, (int, float)) and not isinstance(value, bool):
            return None if math.isfinite(value) else "a finite number"
        if k in (str, list, dict) and isinstance(value, k):
            return None
    names = {int: "a whole number", float: "a number", str: "a string", bool: "true or false", list: "a list",
             dict: "an object", type(None): "null"}
    return " or ".join(names.get(k, k.__name__) for k in kinds)


def check_field(f, value):
    """Error text for ``value`` of dataclass field ``f`` (None when valid)."""
    meta = f.metadata
    if meta.get("choices") is not None:
        if value in meta["choices"] and type(value) in {type(c) for c in meta["choices"]}:
            return None
        return f"one of {', '.join(json.dumps(c) for c in meta['choices'])}"
    why = _type_error(value, f.type)
    if why:  # a field with its own check says what it takes better than its type's names
        return (meta["check"](value) or why) if meta.get("check") is not None else why
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        low, high, above = meta.get("low"), meta.get("high"), meta.get("above")
        if low is not None and value < low or high is not None and value > high or above is not None \
                and value <= above:
            parts = [f"> {above:g}" if above is not None else f">= {low:g}" if low is not None else None,
                     f"<= {high:g}" if high is not None else None]
            return "a number " + " and ".join(p for p in parts if p)
    if meta.get("check") is not None:
        return meta["check"](value)
    return None


class Settings:
    """Mixin for ``@dataclass`` settings: validation, sources, JSON and help text.

    ``ADDED`` (a class attribute): settings added after runs were recorded, each with the value that
    leaves a fit as it was before the setting existed; a run's config.json without one reads as that
    value (:meth:`recorded`), so a finished run stays comparable and reusable."""
    ADDED = {}

    def __post_init__(self):
        for f in dataclasses.fields(self):
            why = check_field(f, getattr(self, f.name))
            if why:
                raise ValueError(f"{f.name} must be {why}, got {_show(getattr(self, f.name))}")

    def check(self):
        """Checks of the settings as a whole, made once they are complete (:meth:`from_sources` calls
        it; override and raise ``ValueError``)."""

    @classmethod
    def names(cls):
        return [f.name for f in dataclasses.fields(cls)]

    def replace(self, **changes):
        unknown = sorted(set(changes) - set(self.names()))
        if unknown:
            raise ValueError(f"unknown setting{'s' if len(unknown) > 1 else ''} {', '.join(unknown)} "
                             f"(see --help for the list)")
        return dataclasses.replace(self, **changes)

    def to_dict(self):
        return dataclasses.asdict(self)

    @classmethod
    def recorded(cls, data):
        """The settings a run's config.json object ``data`` holds: the record keys left out, the
        settings added since (``ADDED``) at the values that fitted as it was fitted where it lacks them."""
        return {**cls.ADDED, **{k: v for k, v in data.items() if k not in RECORD_KEYS}}

    @classmethod
    def from_sources(cls, path=None, overrides=(), **values):
        """Defaults, then the JSON object in ``path`` (a settings file, or a run's config.json, whose
        record keys are skipped), then ``values``, then ``--set`` ``overrides`` ("name=value", the
        value read as JSON, else as a string). Errors name the key and its source."""
        cfg = cls()
        if path:
            try:
                with open(path) as f:
                    data = json.load(f)
            except OSError as e:
                raise ValueError(f"{path}: cannot read settings ({e.strerror})") from None
            except ValueError as e:
                raise ValueError(f"{path}: not valid JSON ({e})") from None
            if not isinstance(data, dict):
                raise ValueError(f"{path}: settings must be a JSON object of name: value, got a "
                                 f"{type(data).__name__}")
            try:
                cfg = cfg.replace(**cls.recorded(data))
            except (TypeError, ValueError) as e:
                raise ValueError(f"{path}: {e}") from None
        try:
            cfg = cfg.replace(**values)
        except (TypeError, ValueError) as e:
            raise ValueError(str(e)) from None
        for item in overrides:
            name, sep, value = item.partition("=")
            if not sep or not name:
                raise ValueError(f"--set expects name=value, got '{item}'")
            try:
                cfg = cfg.replace(**{name.strip(): parse_value(value)})
            except (TypeError, ValueError) as e:
                raise ValueError(f"--set {item}: {e}") from None
        cfg.check()
        return cfg

    @classmethod
    def help_text(cls, title="settings"):
        """Every setting with its default and comment, for ``--help``."""
        lines = [f"{title} (--set name=value, or --config FILE with a JSON object):"]
        for f in dataclasses.fields(cls):
            default = f.default_factory() if f.default is dataclasses.MISSING else f.default
            lines.append(f"  {f.name} = {json.dumps(default)}")
            lines.append(f"      {f.metadata.get('help', '')}")
        return "\n".join(lines)


def _show(value):
    try:
        return json.dumps(value)
    except (TypeError, ValueError):
        return repr(value)


def parse_value(text):
    """A ``--set`` value: JSON when it parses (numbers, lists, true/false, null, quoted strings), else
    the text itself."""
    try:
        return json.loads(text)
    except json.JSONDecodeError:
        return text

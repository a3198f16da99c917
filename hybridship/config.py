"""Validated settings: pydantic dataclasses whose errors name the field.

The package's settings objects (``EnsembleConfig``, ``DPLossConfig``, ``SeaState``, ...)
are declared with :func:`config_dataclass`: a :func:`pydantic.dataclasses.dataclass` with
field constraints (``Field(gt=..., ge=..., le=...)``, ``Literal``) and ``model_validator``\\ s
for the cross-field rules. They keep dataclass semantics (positional construction,
:func:`dataclasses.replace`, which re-validates, and :func:`dataclasses.asdict`, used by
the model files), refuse unknown keywords, NaN and infinity, and raise a plain
:class:`ValueError` whose message starts with the field name, e.g.::

    ValueError: n_members: must be >= 1 (got 0) [EnsembleConfig]

The same formatter words the vessel-file errors (:func:`hybridship.vessel.vessel_from_dict`).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import re
from collections.abc import Mapping
from typing import Annotated

import numpy as np
from pydantic import AfterValidator, BeforeValidator, ConfigDict, Field, ValidationError
from pydantic.dataclasses import dataclass as _pydantic_dataclass

__all__ = ["Bool", "check_flags", "check_number", "check_whole_number", "real_array", "config_dataclass", "format_validation_error", "Int", "Float", "NonEmpty", "non_empty", "float_array",
           "start_time_rng"]


#: Plain wording of pydantic's common error types (by ``type``; ``{name}`` from its ``ctx``).
_PLAIN_MESSAGES = {
    "greater_than": "must be > {gt}", "greater_than_equal": "must be >= {ge}",
    "less_than": "must be < {lt}", "less_than_equal": "must be <= {le}",
    "float_parsing": "expected a number", "float_type": "expected a number",
    "int_parsing": "expected a whole number", "int_type": "expected a whole number",
    "int_from_float": "expected a whole number", "finite_number": "expected a finite number",
    "bool_parsing": "expected true or false", "bool_type": "expected true or false",
    "string_type": "expected text", "string_pattern_mismatch": "expected text matching {pattern}",
    "literal_error": "expected {expected}",
    "extra_forbidden": "not a known field", "unexpected_keyword_argument": "not a known field",
    "missing": "missing (required)", "missing_argument": "missing (required)",
}


def _plain_message(e: dict) -> str:
    """``e``'s message in the project's words where its type is a common one, else pydantic's."""
    template = _PLAIN_MESSAGES.get(e["type"])
    ctx = {k: (f"{v:.10g}" if isinstance(v, float) else v) for k, v in (e.get("ctx") or {}).items()}
    try:
        return template.format(**ctx) if template else e["msg"].removeprefix("Value error, ")
    except (KeyError, ValueError):
        return e["msg"].removeprefix("Value error, ")


def format_validation_error(err: ValidationError, source: str | None = None) -> str:
    """One line per error: ``[source: ]field.path[i]: message (got value)``.

    Common error types are worded plainly (``must be > 0``, ``expected a number``; see
    :data:`_PLAIN_MESSAGES`). Errors raised by a model validator (no field location) whose
    message already starts with the field name are given as they are.
    """
    lines = []
    for e in err.errors():
        loc = ""
        for part in e["loc"]:
            loc += f"[{part}]" if isinstance(part, int) else (f".{part}" if loc else str(part))
        msg = _plain_message(e)
        got = (f" (got {e['input']!r})" if e["type"] not in ("missing", "value_error")
               and not isinstance(e["input"], dict) else "")
        head = f"{source}: " if source is not None else ""
        if loc:
            lines.append(f"{head}{loc}: {msg}{got}")
        elif source is not None and not re.match(r"[\w.\[\]/]+: ", msg):
            lines.append(f"{head}<top level>: {msg}{got}")
        else:   # a model validator's message that names its field already
            lines.append(f"{head}{msg}{got}")
    return "\n".join(lines)


def settings_error(err: ValidationError, class_name: str, prefix: str | None = None) -> ValueError:
    """The ValueError a settings class raises for ``err``: :func:`format_validation_error`'s
    lines, each ending in ``[class_name]`` (and starting with ``prefix.`` when given)."""
    head = f"{prefix}." if prefix else ""
    return ValueError("\n".join(f"{head}{line} [{class_name}]" for line in format_validation_error(err).split("\n")))


def _not_bool(v):
    if isinstance(v, (bool, np.bool_)):
        raise ValueError(f"expected an integer, not a bool ({v!r})")
    if isinstance(v, (str, bytes)):
        raise ValueError(f"expected an integer, got {v!r}")
    return v


def _number(v):
    if isinstance(v, (bool, np.bool_, str, bytes)):
        raise ValueError(f"expected a number, got {v!r}")
    return v


#: An ``int`` field that refuses ``True``/``False`` (numpy's too; pydantic would read them as 1/0)
#: and strings (pydantic would parse ``"2"``); numpy integers are accepted.
Int = Annotated[int, BeforeValidator(_not_bool)]

def _bool_only(v):
    if isinstance(v, np.bool_):
        return bool(v)
    if not isinstance(v, bool):
        raise ValueError(f"expected True or False, got {v!r}")
    return v


#: A ``bool`` field that refuses text and numbers (pydantic would read ``"no"`` and ``1``).
Bool = Annotated[bool, BeforeValidator(_bool_only)]

#: A random seed: a non-negative ``int`` below 2**63 (numpy's and torch's generators both
#: take it; a negative or larger one used to fail deep inside them).
Seed = Annotated[int, BeforeValidator(_not_bool), Field(ge=0, lt=2**63)]


def real_array(name: str, a) -> np.ndarray:
    """``a`` as a float array, or a TypeError naming ``name``: text and complex numbers are
    refused (numpy would parse ``"1.5"``, drop an imaginary part with only a warning, or fail
    in its own words). Rows of different lengths are a ValueError naming ``name`` (numpy's
    was "setting an array element with a sequence ... inhomogeneous shape")."""
    try:
        arr = np.asarray(a)
    except ValueError:
        raise ValueError(f"{name}: expected an array of numbers, got rows of different lengths") from None
    if arr.dtype.kind in "USc":
        raise TypeError(f"{name}: expected an array of real numbers, got dtype {arr.dtype}")
    if arr.dtype.kind == "O" and any(isinstance(x, (str, bytes, complex)) for x in arr.flat):
        # a pandas column of text ('1500') is an object array, which astype(float) parses
        raise TypeError(f"{name}: expected an array of real numbers, got text or complex numbers (dtype object)")
    try:
        return arr.astype(float, copy=False)
    except (TypeError, ValueError):
        raise TypeError(f"{name}: expected an array of real numbers, got {type(a).__name__}") from None


def check_flags(optional=(), **flags) -> None:
    """TypeError naming a flag that is not True or False (None where ``optional``): a text
    'no' or 'false' is truthy and would be read as True."""
    for name, value in flags.items():
        if not (isinstance(value, (bool, np.bool_)) or (name in optional and value is None)):
            raise TypeError(f"{name}: expected True or False{' or None' if name in optional else ''}, got {value!r}")


def start_time_rng(seed: int, time_s: float) -> np.random.Generator:
    """The random generator of one forecast start, keyed by ``seed`` and the bits of its start
    time ``time_s`` [s]: a start's draws do not depend on the other starts of a batch, nor on
    which rows of the log were read (a row index would move with them)."""
    return np.random.default_rng([int(seed), int(np.float64(time_s).view(np.uint64))])


def non_empty(v):
    """After-validator of a sequence field: at least one item (``Annotated[tuple[...], AfterValidator(non_empty)]``;
    unlike ``Field(min_length=1)`` it does not add a second error when an item is invalid)."""
    if len(v) == 0:
        raise ValueError("expected at least one value")
    return v


#: A ``float`` field that refuses bools and strings (pydantic would parse ``"1.5"``);
#: numpy scalars are accepted. NaN and infinity are refused by every config.
Float = Annotated[float, BeforeValidator(_number)]

def float_array(shape: tuple | None = None, *, flat: bool = False, finite: bool = True,
                lo: float | None = None, lo_open: bool = False, readonly: bool = False):
    """A numpy-array field (needs ``config_dataclass(arbitrary_types=True)``): the input is
    copied to a float array (the caller's array is never shared), raveled with ``flat``,
    and checked for its ``shape``, finiteness and lower bound ``lo``. Text and complex
    numbers are refused, as by :func:`real_array`."""
    def convert(v):
        try:
            a = real_array("array", v).copy()       # a copy: never the caller's array
        except (TypeError, ValueError) as err:      # a ValueError, which pydantic reports under the field's name
            raise ValueError(str(err).removeprefix("array: ")) from None
        if flat:
            a = a.reshape(-1)
        if shape is not None and a.shape != shape:
            raise ValueError(f"expected shape {shape}, got {a.shape}")
        if finite and not np.all(np.isfinite(a)):
            raise ValueError("must be finite (no NaN or inf)")
        if lo is not None and np.any(a <= lo if lo_open else a < lo):
            raise ValueError(f"every entry must be {'>' if lo_open else '>='} {lo:g}")
        if readonly:
            a.setflags(write=False)
        return a

    return Annotated[np.ndarray, BeforeValidator(convert)]


#: Marks a sequence field that needs at least one item: ``Annotated[tuple[Float, ...], NonEmpty]``.
NonEmpty = AfterValidator(non_empty)


def config_dataclass(cls=None, /, *, frozen: bool = False, arbitrary_types: bool = False,
                     prefix: str | None = None, **kwargs):
    """Declare a validated settings dataclass (see the module docstring).

    Parameters
    ----------
    frozen : bool
        As for :func:`dataclasses.dataclass`.
    arbitrary_types : bool
        Allow fields of non-pydantic types (e.g. numpy arrays, checked by validators).
    prefix : str, optional
        Written before the field names in error messages (``"weather"`` gives
        ``weather.hs_m: ...``), for settings that usually sit inside another object.
    **kwargs
        Passed on to :func:`pydantic.dataclasses.dataclass` (e.g. ``eq=False``).
    """
    def wrap(c):
        config = ConfigDict(extra="forbid", allow_inf_nan=False, arbitrary_types_allowed=arbitrary_types)
        dc = _pydantic_dataclass(c, frozen=frozen, config=config, **kwargs)
        init = dc.__init__
        names = [f.name for f in dataclasses.fields(dc)]

        @functools.wraps(init)
        def __init__(self, *args, **kw):
            if args and len(args) <= len(names) and not set(names[:len(args)]) & set(kw):
                # Positional arguments by name, so that an error names the field.
                kw = {**dict(zip(names, args)), **kw}
                args = ()
            try:
                init(self, *args, **kw)
            except ValidationError as err:
                raise settings_error(err, dc.__name__, prefix) from None     # every problem names its class

        dc.__init__ = __init__
        return dc

    return wrap if cls is None else wrap(cls)


def as_config(value, cls, name: str):
    """A settings argument as an instance of the config class ``cls``.

    An instance passes as it is; a mapping becomes ``cls(**value)``, validated (an unknown
    or misspelt key is refused by name); anything else is a TypeError naming the argument
    ``name``. For the constructors that take settings objects, so that a dict with a typo
    fails here and not as an attribute error deep inside training.
    """
    if isinstance(value, cls):
        return value
    if isinstance(value, Mapping):
        try:
            return cls(**value)
        except ValidationError as err:   # a pydantic model's own, unformatted
            raise ValueError(f"{name}: {format_validation_error(err)}") from None
        except (TypeError, ValueError) as err:
            raise type(err)(f"{name}: {err}") from None
    raise TypeError(f"{name}: expected an instance of {cls.__name__} (or a dict of its fields), "
                    f"got {type(value).__name__}")


def check_number(name: str, value, *, lo=None, hi=None, lo_open: bool = False, allow_none: bool = False):
    """``value`` as a finite float within ``[lo, hi]`` (``(lo, hi]`` with ``lo_open``), or an
    error naming ``name`` and what was expected (TypeError for a non-number, ValueError
    otherwise). ``allow_none`` passes None through."""
    if value is None and allow_none:
        return None
    if isinstance(value, (bool, np.bool_, str, bytes)):     # float() would read "60" and True as numbers
        raise TypeError(f"{name}: expected a number, got {value!r}")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise TypeError(f"{name}: expected a number, got {value!r}") from None
    except OverflowError:       # a whole number beyond a float's range (10**400)
        raise ValueError(f"{name}: must be finite, got a number beyond a float's range") from None
    if not math.isfinite(v):
        raise ValueError(f"{name}: must be finite, got {value!r}")
    if lo is not None and (v <= lo if lo_open else v < lo):
        raise ValueError(f"{name}: must be {'>' if lo_open else '>='} {lo:g}, got {value!r}")
    if hi is not None and v > hi:
        raise ValueError(f"{name}: must be <= {hi:g}, got {value!r}")
    return v


def check_whole_number(name: str, value, lo: int = 0) -> int:
    """``value`` as an ``int`` of at least ``lo`` (numpy integers accepted; bools, floats and
    text refused), or a ValueError naming ``name`` and what was expected."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < lo:
        raise ValueError(f"{name}: expected a whole number >= {lo}, got {value!r}")
    return int(value)

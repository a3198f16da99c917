"""How errors are worded for people: one line per problem.

Kept free of heavy imports: the command line uses it on every error, and ``hybridship
--help`` should stay fast.
"""

from __future__ import annotations

import os
import re
import sys
import warnings

__all__ = ["problem_lines", "seconds_text", "warn_user"]

_PACKAGE_DIR = os.path.dirname(os.path.abspath(__file__)) + os.sep

#: Decimals of a time in messages: a microsecond, finer than any log's sample spacing.
TIME_DECIMALS = 6


#: The settings class a library message names at the end of a line (``... [DPLossConfig]``):
#: useful from Python, noise on the command line, where the option is named instead.
#: A CamelCase name only (two capitals and a lower-case letter), so that a unit such as
#: ``[N]`` or ``[kN m]`` at a line's end stays.
_CLASS_SUFFIX = re.compile(r" \[(?=[A-Za-z0-9]*[a-z])(?=(?:[a-z0-9]*[A-Z]){2})[A-Z][A-Za-z0-9]{3,}\]$")


def problem_lines(exc: BaseException, head: str = "", option_of=None) -> str:
    """``exc``'s message as one line per problem, each starting with ``head``.

    A validation error lists every mistake of a file or a settings object on a line of
    its own (:func:`hybridship.config.format_validation_error`); whitespace inside a line
    is collapsed so that each problem stays one line, and the settings class named at its
    end is dropped. With ``option_of`` (field name -> option), each line's leading field
    (``field: ...``) is replaced by the option the user typed. The command line prints its
    errors this way.
    """
    lines = [_CLASS_SUFFIX.sub("", " ".join(line.split())) for line in str(exc).splitlines()]
    if option_of is not None:
        named = []
        for line in lines:
            field, sep, rest = line.partition(":")
            named.append(f"{option_of(field)}{sep}{rest}" if sep else line)
        lines = named
    return "\n".join(f"{head}{line}" for line in lines if line) or f"{head}{type(exc).__name__}"


def seconds_text(t: float) -> str:
    """A time [s] as written in messages: to the microsecond, without an exponent, so that the
    epoch times of a log (1.7e9 s) stay distinct ("1700000000.5", not "1.7e+09")."""
    text = f"{round(float(t), TIME_DECIMALS):.{TIME_DECIMALS}f}".rstrip("0").rstrip(".")
    return "0" if text in ("", "-0") else text


def warn_user(message: str, category: type[Warning] = UserWarning) -> None:
    """Warn at the first line outside this package: the user's call.

    A fixed ``stacklevel`` counts frames from the warning, and a function reached through
    another of the package's functions or a decorator (``fit`` runs under one) placed the
    warning at library code, where the user's warning filters on their own module miss it.
    The frames are counted as pandas' ``find_stack_level`` counts them.
    """
    frame, level = sys._getframe(1), 2     # level 2: the caller of warn_user
    while frame is not None and os.path.abspath(frame.f_code.co_filename).startswith(_PACKAGE_DIR):
        frame, level = frame.f_back, level + 1
    warnings.warn(message, category, stacklevel=level)

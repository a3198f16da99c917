"""How errors are worded for people: one line per problem.

Kept free of heavy imports: the command line uses it on every error, and ``hybridship
--help`` should stay fast.
"""

from __future__ import annotations

__all__ = ["problem_lines"]


def problem_lines(exc: BaseException, head: str = "") -> str:
    """``exc``'s message as one line per problem, each starting with ``head``.

    A validation error lists every mistake of a file or a settings object on a line of
    its own (:func:`hybridship.config.format_validation_error`); whitespace inside a line
    is collapsed so that each problem stays one line. The command line prints its errors
    this way.
    """
    lines = [" ".join(line.split()) for line in str(exc).splitlines()]
    return "\n".join(f"{head}{line}" for line in lines if line) or f"{head}{type(exc).__name__}"

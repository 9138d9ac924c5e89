"""Exceptions raised by vidiscover.

Every error a user can cause by giving bad input is an :class:`InputError`: a
one-line message naming *what* is wrong, *where* (file, column, parameter) and
*how to fix it*. The CLI turns it into a message on stderr and exit status 2.
"""

from __future__ import annotations

__all__ = ["InputError", "SimulationError"]


class InputError(ValueError):
    """Bad input given by the user (file, metadata, parameter or option).

    The message is a single line; ``str(err)`` is what the CLI prints.
    """

    def __init__(self, message: str) -> None:
        super().__init__(" ".join(str(message).split()))


class SimulationError(RuntimeError):
    """A simulation that could not be carried through (an integrator that gave up).

    Not the user's input: a drawn case of a training or benchmark set may hit it, and
    the set then records the case as dropped with this message instead of stopping.
    """

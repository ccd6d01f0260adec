"""The one step every engine takes: look its (state, event) up in its transition table.

Engines move only through their tables (the tests walk every transition); a move the table
lacks is the engine's own bug, said as one `LocalProtocolError` naming the engine.
"""

from __future__ import annotations

from enum import Enum
from typing import Mapping, TypeVar

from .errors import LocalProtocolError

S = TypeVar("S", bound=Enum)


class TableEnum(Enum):
    """An Enum hashed by identity, for states and events a hot engine looks up on every step.

    Enum's own `__hash__` hashes the member's name in Python code, twice per table lookup;
    members are singletons compared by identity, so identity is as good a hash, and C-fast."""

    __hash__ = object.__hash__


def next_state(table: Mapping[tuple[S, Enum], S], state: S, event: Enum, engine: str) -> S:
    """The state `event` leads to from `state`; LocalProtocolError if the table has no such move."""
    try:
        return table[(state, event)]
    except KeyError:
        raise LocalProtocolError(f"{engine}: no transition for {event.name} in {state.name}") from None

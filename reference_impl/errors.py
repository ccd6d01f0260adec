"""Two kinds of error, never confused (after h11's Local/RemoteProtocolError split).

- `UsageError`: the user's mistake (bad URI, file, option). One line naming what and
  where; the CLI turns it into exit code 2.
- `LocalProtocolError`: this program was asked to do something the protocol forbids
  (start a second operation on a busy client, send a v1 frame with a 24-bit id). A bug in
  the caller, raised at once.

What a *remote* peer does wrong is not an exception at all: it is a finding, returned as a
value (a `DecodeError`, a failed operation result) and reported.
"""


class UsageError(ValueError):
    """A user mistake: bad URI, file, option. `str()` is the one-line message."""


class LocalProtocolError(RuntimeError):
    """The caller asked an engine for something the protocol does not allow now."""

"""The admission rule's stream models: the C parser's variants, grouped while they are in
the same state (they part only on rare frames: see CParser.diverged), so each datagram is
parsed once per group (fuzz/frames/admission.py)."""

from __future__ import annotations

from mavconform.reference_impl.wire.cparser import OK, CParser, ParsedFrame

Models = list[tuple[tuple[str, ...], CParser]]


def stream_offending(models: Models, data: bytes,
                     inert: frozenset[int]) -> tuple[Models, list[tuple[ParsedFrame, int]]]:
    """The models fed with `data` (copies), and every offending frame with the stream
    offset `data` started at: completed OK, or pending with a good checksum that any
    signature bytes complete, and not INERT (msgids in `inert`). (The same frame may come
    twice, once per variant.)"""
    trial: Models = []
    hits: list[tuple[ParsedFrame, int]] = []
    for variants, m in models:
        t = m.copy()
        base = t.offset
        frames = t.feed(data, variants[0])
        if len(variants) == 1 or not t.diverged:     # the usual case, inline
            for f in frames:
                if f.result == OK and f.msgid not in inert:
                    hits.append((f, base))
            if t._buf:
                p = t.awaiting_signature()
                if p is not None and p.msgid not in inert:
                    hits.append((p, base))
            trial.append((variants, t))
            continue
        # a frame the variants part on: the others parse on their own from here
        _offending(frames, t, base, hits, inert)
        trial.append((variants[:1], t))
        for v in variants[1:]:
            tv = m.copy()
            _offending(tv.feed(data, v), tv, base, hits, inert)
            trial.append(((v,), tv))
    if len(trial) > 1:
        trial = _merged(trial)
    return trial, hits


def _offending(frames: list[ParsedFrame], model: CParser, base: int,
               hits: list[tuple[ParsedFrame, int]], inert: frozenset[int]) -> None:
    for f in frames:
        if f.result == OK and f.msgid not in inert:
            hits.append((f, base))
    p = model.awaiting_signature()
    if p is not None and p.msgid not in inert:
        hits.append((p, base))


def _merged(models: Models) -> Models:
    """Groups whose states are equal made one again."""
    out: Models = []
    for variants, m in models:
        for k, (others, o) in enumerate(out):
            if m.same_state(o):
                out[k] = (others + variants, o)
                break
        else:
            out.append((variants, m))
    return out


def bytes_to_idle(model: CParser, variant: str, filler: int, limit: int) -> int:
    """How many filler bytes (at most `limit`) bring `model` to IDLE (it stays IDLE after:
    no start byte)."""
    if model.idle:
        return 0
    lo, hi = 1, limit
    while lo < hi:
        mid = (lo + hi) // 2
        t = model.copy()
        t.feed(bytes((filler,)) * mid, variant)
        if t.idle:
            hi = mid
        else:
            lo = mid + 1
    return lo

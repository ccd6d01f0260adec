"""The GCSs the authenticity tests know, and their signing keys (test_authenticity*.py)."""

from __future__ import annotations

import hashlib

from mavconform.reference_impl.wire.signing import SigningKey

A, B, STRANGER = 201, 202, 66


def key(word: str, link_id: int) -> SigningKey:
    return SigningKey(hashlib.sha256(word.encode()).digest(), link_id)


KEY_A, KEY_B, KEY_X = key("A", 1), key("B", 2), key("nobody", 3)

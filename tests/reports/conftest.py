import pytest

from .sample import run_document


@pytest.fixture
def doc():
    """A fresh, valid run document with every outcome and hostile target text."""
    return run_document()

"""Shared for the vectors tests: our dialect, the committed set, and a dialect with a message
another helper might add (to show regeneration picks it up)."""

from __future__ import annotations

from pathlib import Path

import pytest

from mavconform.reference_impl.wire.dialect import XML_PATH
from mavconform.vectors import store
from mavconform.vectors.dialect_info import DialectInfo, load_dialect

ADDED_MESSAGE = """    <message id="600" name="VECTORS_TEST_ADDED">
      <description>A message the vectors tests add to a copy of our dialect.</description>
      <field type="uint8_t" name="target_system">System.</field>
      <field type="int32_t" name="lat" units="degE7">Latitude.</field>
      <field type="int32_t" name="lon" units="degE7">Longitude.</field>
      <field type="double" name="value">A double.</field>
      <field type="char[10]" name="label">A short text.</field>
      <field type="int16_t[3]" name="triple">Three signed numbers.</field>
      <extensions/>
      <field type="float" name="extra">An extension.</field>
    </message>
  </messages>"""


@pytest.fixture(scope="session")
def dialect() -> DialectInfo:
    return load_dialect()


@pytest.fixture(scope="session")
def committed() -> store.VectorSet:
    return store.load(store.DATA_DIR)


@pytest.fixture(scope="session")
def added_xml(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Our dialect XML plus one message (id 600) with a double, a char array, an int16 array,
    lat/lon fields and an extension."""
    path = tmp_path_factory.mktemp("dialect") / "vectors_test_dialect.xml"
    text = XML_PATH.read_text()
    assert text.count("  </messages>") == 1
    path.write_text(text.replace("  </messages>", ADDED_MESSAGE))
    return path

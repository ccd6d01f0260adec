"""Which messages get vectors, and their wire layout, read from a dialect XML.

The rule (docs/vectors.md): every message *defined in* the dialect XML file, in id order,
not those of the files it includes. For our own dialect (`mavconform_dialect.xml`, no
includes) that is every message the mission and handover protocols use, so a message
another helper adds to it gets vectors on the next `mavconform vectors generate`; for a
user's dialect that includes common.xml, it is the user's own messages.

The layout comes from pymavlink's mavparse (the same parser mavgen uses for every
language), the encoder from the Python module mavgen makes of the XML: ours is committed
(`reference_impl/wire/dialect`), a user's is generated into a temporary directory.
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib.util
import io
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.wire.codec import base_payload_length
from mavconform.reference_impl.wire.dialect import XML_PATH as OUR_XML
from mavconform.reference_impl.wire.dialect import mavlink as our_module

INT_RANGES: dict[str, tuple[int, int]] = {
    "uint8_t": (0, 0xFF), "int8_t": (-0x80, 0x7F),
    "uint16_t": (0, 0xFFFF), "int16_t": (-0x8000, 0x7FFF),
    "uint32_t": (0, 0xFFFF_FFFF), "int32_t": (-0x8000_0000, 0x7FFF_FFFF),
    "uint64_t": (0, 0xFFFF_FFFF_FFFF_FFFF), "int64_t": (-0x8000_0000_0000_0000, 0x7FFF_FFFF_FFFF_FFFF),
}
FLOAT_TYPES = frozenset({"float", "double"})


@dataclass(frozen=True)
class FieldInfo:
    name: str
    type: str                 # C base type: uint8_t ... double, char
    array_length: int         # 0: a scalar; char[n] is a string of at most n bytes
    extension: bool
    units: str                # as the XML writes it, e.g. "degE7" ("" if none)
    const_value: int | None   # uint8_t_mavlink_version: the encoder writes the dialect version

    @property
    def is_float(self) -> bool:
        return self.type in FLOAT_TYPES

    @property
    def is_string(self) -> bool:
        return self.type == "char"


@dataclass(frozen=True)
class MessageInfo:
    name: str
    id: int
    crc_extra: int
    fields: tuple[FieldInfo, ...]    # in XML order (base fields, then extensions)
    base_length: int                 # payload bytes of the base fields (MAVLink 1 length)
    max_length: int                  # payload bytes with every extension
    cls: Any                         # the generated pymavlink message class

    @property
    def has_extensions(self) -> bool:
        return any(f.extension for f in self.fields)

    @property
    def fits_v1(self) -> bool:
        return self.id <= 0xFF


@dataclass(frozen=True)
class DialectInfo:
    xml_path: Path
    xml_sha256: str
    version: int              # the XML's <version>: what uint8_t_mavlink_version carries
    module: Any               # the generated pymavlink module (FrameEncoder's `dialect`)
    messages: tuple[MessageInfo, ...]
    all_ids: frozenset[int]   # every id the module decodes, includes too

    @property
    def is_ours(self) -> bool:
        return self.xml_path == OUR_XML


def load_dialect(xml: str | Path | None = None) -> DialectInfo:
    """Our dialect (None), or a user's XML: parsed, and its Python module made by mavgen.
    A missing or unparsable file is a UsageError naming it."""
    path = Path(xml).resolve() if xml is not None else OUR_XML
    if not path.is_file():
        raise UsageError(f"--dialect {xml}: no such file")
    module = our_module if path == OUR_XML else _generate_module(path)
    from pymavlink.generator import mavparse
    try:
        with contextlib.redirect_stdout(io.StringIO()):   # mavparse narrates enum warnings
            parsed = mavparse.MAVXML(str(path), mavparse.PROTOCOL_2_0)
    except Exception as exc:   # mavparse raises MAVParseError, ExpatError, KeyError...
        raise UsageError(f"--dialect {xml}: not a MAVLink dialect XML: {_first_line(exc)}") from None
    messages = []
    for m in sorted(parsed.message, key=lambda m: m.id):
        cls = module.mavlink_map.get(m.id)
        if cls is None:
            raise UsageError(f"--dialect {xml}: mavgen made no class for {m.name} (id {m.id})")
        ext = m.extensions_start if m.extensions_start is not None else len(m.fields)
        fields = tuple(
            FieldInfo(f.name, f.type, f.array_length, i >= ext, f.units.strip("[]"),
                      parsed.version if getattr(f, "omit_arg", False) else None)
            for i, f in enumerate(m.fields))
        messages.append(MessageInfo(m.name, m.id, m.crc_extra, fields, base_payload_length(cls),
                                    m.wire_length, cls))
    if not messages:
        raise UsageError(f"--dialect {xml}: the file defines no message")
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    return DialectInfo(path, digest, parsed.version, module, tuple(messages), frozenset(module.mavlink_map))


def _generate_module(path: Path) -> Any:
    """mavgen's Python module for a user's XML (includes resolved beside it), imported from a
    temporary directory under a private name."""
    from pymavlink.generator import mavgen
    with tempfile.TemporaryDirectory() as tmp:
        target = Path(tmp) / f"{path.stem}.py"
        opts = mavgen.Opts(str(target), wire_protocol="2.0", language="Python3", validate=False)
        log = io.StringIO()
        with contextlib.redirect_stdout(log), contextlib.redirect_stderr(log):
            try:
                ok = mavgen.mavgen(opts, [str(path)])
            except Exception as exc:
                raise UsageError(f"--dialect {path}: mavgen failed: {_first_line(exc)}") from None
        if not ok or not target.is_file():
            raise UsageError(f"--dialect {path}: mavgen failed: {_first_line(log.getvalue())}")
        name = f"_mavconform_user_dialect_{hashlib.sha256(str(path).encode()).hexdigest()[:12]}"
        spec = importlib.util.spec_from_file_location(name, target)
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return module


def _first_line(value: object) -> str:
    text = str(value).strip()
    return text.splitlines()[-1][:200] if text else type(value).__name__

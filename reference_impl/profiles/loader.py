"""Reading profile files: the bundled ones (BUILTIN_PROFILES: `spec`, `px4` and its fixed-wing
and VTOL, `ardupilot` and its plane and rover, `inav`), or a user's own.

    name = "my-fork"
    description = "our PX4 fork: retries capped again"
    base = "px4"                       # a bundled name, or a file path (relative to this one)

    [[knob]]
    knob = "retry_cap"
    value = true
    variant = "P3"                     # optional in a user file; required in bundled ones
    source = "our fork, commit abc123"
    why = "we cap retries at 5"
    seen_on = "our fork v2.1 SITL"     # optional: the real version it was observed on

A knob set again replaces the base's setting. `[[documented]]` tables (variant, kind =
"same-as-spec" | "not-reproduced", why, source) record rows that need no knob. Any mistake
(unknown knob, bad value, unknown key, unreadable file) is one `UsageError` naming the file
and the key.
"""

from __future__ import annotations

import dataclasses
import inspect
import sys
from pathlib import Path
from typing import Any, Sequence

from ..errors import UsageError
from ..flight_rules import FlightRules
from ..mission.behaviour import ServerBehaviour
from ..mission.timing import Timings
from ..mission.validation import rules_for
from ..vehicle import VehicleConfig
from .knobs import BEHAVIOUR, CONFIG, FLIGHT, KNOBS, RULES, TIMINGS
from .model import Alternative, Documented, KnobSetting, Profile

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

BUNDLED = Path(__file__).parent
BUILTIN_PROFILES: tuple[str, ...] = ("spec", "px4", "px4-fixedwing", "px4-vtol", "ardupilot", "ardupilot-plane",
                                     "ardupilot-rover", "inav")
MAX_BASE_DEPTH = 8
_TOP_KEYS = {"name", "description", "base", "knob", "documented"}
_KNOB_KEYS = {"knob", "value", "variant", "source", "why", "alternative", "seen_on"}
_ALT_KEYS = {"value", "variant", "source", "why"}
_DOC_KEYS = {"variant", "kind", "why", "source"}
DOC_KINDS = ("same-as-spec", "not-reproduced")


def resolve(name_or_path: str, relative_to: Path | None = None) -> Path:
    if name_or_path in BUILTIN_PROFILES:
        return BUNDLED / f"{name_or_path}.toml"
    path = Path(name_or_path)
    if relative_to is not None and not path.is_absolute():
        path = relative_to / path
    if not path.is_file():
        raise UsageError(f"profile {name_or_path!r}: no such profile file or builtin name "
                         f"(builtin: {', '.join(BUILTIN_PROFILES)})")
    return path


def load_profile(name_or_path: str) -> Profile:
    """A builtin profile by name, or a profile file (which may build on another)."""
    return _load(resolve(name_or_path), depth=0)


def _read(path: Path) -> dict[str, Any]:
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise UsageError(f"cannot read profile file {str(path)!r}: {exc.strerror}") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise UsageError(f"{path}: not valid TOML: {exc}") from None


def _load(path: Path, depth: int) -> Profile:
    if depth > MAX_BASE_DEPTH:
        raise UsageError(f"{path}: 'base' chain longer than {MAX_BASE_DEPTH} (a cycle?)")
    data = _read(path)
    unknown = set(data) - _TOP_KEYS
    if unknown:
        raise UsageError(f"{path}: unknown key {sorted(unknown)[0]!r} "
                         f"(expected {', '.join(sorted(_TOP_KEYS))})")
    name = _string(data, "name", path, required=True)
    description = _string(data, "description", path)
    bundled = path.parent.resolve() == BUNDLED.resolve()
    base_settings: tuple[KnobSetting, ...] = ()
    documented: list[Documented] = []
    if "base" in data:
        base_name = _string(data, "base", path, required=True)
        try:
            base = _load(resolve(base_name, relative_to=path.parent), depth + 1)
        except UsageError as exc:
            raise UsageError(f"{path}: base = {base_name!r}: {exc}") from None
        base_settings, documented = base.settings, list(base.documented)
        description = description or base.description
    settings = {s.knob: s for s in base_settings}
    own: dict[tuple[str, str], str] = {}   # (where, field) -> the knob this file sets it with
    for i, entry in enumerate(_tables(data, "knob", path)):
        setting = _setting(entry, f"{path}: knob[{i}]", strict=bundled)
        target = _target(setting.knob)
        if own.setdefault(target, setting.knob) != setting.knob:
            raise UsageError(f"{path}: knob[{i}] ({setting.knob}): sets what knob {own[target]!r} "
                             "sets too; keep one of them")
        for other in [k for k in settings if k != setting.knob and _target(k) == target]:
            del settings[other]            # e.g. mission_commands replaces a base's accept_unknown_commands
        settings[setting.knob] = setting   # a later setting replaces the base's
    for i, entry in enumerate(_tables(data, "documented", path)):
        documented.append(_documented(entry, f"{path}: documented[{i}]"))
    ordered = tuple(settings.values())
    behaviour, config = _build(ordered, path)
    return Profile(name, description, behaviour, config, ordered, tuple(documented), str(path))


def _target(knob: str) -> tuple[str, str]:
    """Where a knob lands: two knobs may set the same engine field (accept_unknown_commands
    and mission_commands both set the item rules' commands), and only one of them can be in force."""
    return KNOBS[knob].where, KNOBS[knob].field


def _string(data: dict, key: str, path: Path, *, required: bool = False) -> str:
    value = data.get(key, "")
    if not isinstance(value, str) or (required and not value.strip()):
        raise UsageError(f"{path}: {key!r} must be a non-empty string")
    return value.strip()


def _tables(data: dict, key: str, path: Path) -> list[dict]:
    entries = data.get(key, [])
    if not isinstance(entries, list) or not all(isinstance(e, dict) for e in entries):
        raise UsageError(f"{path}: {key!r} must be an array of tables ([[{key}]])")
    return entries


def _setting(entry: dict, where: str, *, strict: bool) -> KnobSetting:
    extra = set(entry) - _KNOB_KEYS
    if extra:
        raise UsageError(f"{where}: unknown key {sorted(extra)[0]!r} (expected {', '.join(sorted(_KNOB_KEYS))})")
    name = entry.get("knob")
    if name not in KNOBS:
        raise UsageError(f"{where}: unknown knob {name!r} (list them with `mavconform profiles --knobs`)")
    if "value" not in entry:
        raise UsageError(f"{where} ({name}): 'value' is missing")
    _parse(name, entry["value"], f"{where} ({name})")
    text = {k: entry.get(k, "") for k in ("variant", "source", "why")}
    for key, value in text.items():
        if not isinstance(value, str) or (strict and not value.strip()):
            raise UsageError(f"{where} ({name}): {key!r} must be a non-empty string")
    alternative = None
    if "alternative" in entry:
        alt = entry["alternative"]
        if not isinstance(alt, dict) or set(alt) != _ALT_KEYS:
            raise UsageError(f"{where} ({name}): 'alternative' must be a table with exactly "
                             f"{', '.join(sorted(_ALT_KEYS))}")
        _parse(name, alt["value"], f"{where} ({name}).alternative")
        alternative = Alternative(alt["value"], str(alt["variant"]), str(alt["source"]), str(alt["why"]))
    seen_on = entry.get("seen_on", "")
    if not isinstance(seen_on, str):
        raise UsageError(f"{where} ({name}): 'seen_on' must be a string")
    return KnobSetting(name, entry["value"], text["variant"].strip(), text["source"].strip(),
                       text["why"].strip(), alternative, seen_on.strip())


def _documented(entry: dict, where: str) -> Documented:
    extra = set(entry) - _DOC_KEYS
    if extra:
        raise UsageError(f"{where}: unknown key {sorted(extra)[0]!r} (expected {', '.join(sorted(_DOC_KEYS))})")
    for key in ("variant", "kind", "why"):
        if not isinstance(entry.get(key), str) or not entry[key].strip():
            raise UsageError(f"{where}: {key!r} must be a non-empty string")
    if entry["kind"] not in DOC_KINDS:
        raise UsageError(f"{where}: 'kind' must be one of {', '.join(DOC_KINDS)}, got {entry['kind']!r}")
    return Documented(entry["variant"].strip(), entry["kind"], entry["why"].strip(), str(entry.get("source", "")))


def _parse(name: str, value: Any, where: str) -> Any:
    try:
        return KNOBS[name].parse(value)
    except ValueError as exc:
        raise UsageError(f"{where}: bad value: {exc}") from None


def build_config(settings: Sequence[KnobSetting], where: str = "knob settings") -> VehicleConfig:
    """The reference vehicle's config with just these knob settings (every other knob at the
    spec's default): what a profile file builds, without the file. The knob matrix
    (conformance/knob_judges.py) builds its vehicles one knob at a time with it. Settings that
    do not fit together are a `UsageError` naming `where`."""
    for s in settings:
        if s.knob not in KNOBS:
            raise UsageError(f"{where}: unknown knob {s.knob!r}")
        _parse(s.knob, s.value, f"{where} ({s.knob})")
    return _build(tuple(settings), Path(where))[1]


def spec_default(knob: str) -> Any:
    """The engine value a knob has when no profile sets it (the spec vehicle's), to compare
    with `KNOBS[knob].parse(value)`: a profile may set a knob to it (P1', P2', A3), which
    then changes nothing."""
    k = KNOBS[knob]
    if k.where == RULES:
        return inspect.signature(rules_for).parameters[k.field].default
    owner = {BEHAVIOUR: ServerBehaviour, TIMINGS: Timings, CONFIG: VehicleConfig, FLIGHT: FlightRules}[k.where]
    return getattr(owner(), k.field)


def _build(settings: tuple[KnobSetting, ...], path: Path) -> tuple[ServerBehaviour, VehicleConfig]:
    fields: dict[str, dict[str, Any]] = {BEHAVIOUR: {}, TIMINGS: {}, CONFIG: {}, RULES: {}, FLIGHT: {}}
    for s in settings:
        knob = KNOBS[s.knob]
        fields[knob.where][knob.field] = knob.parse(s.value)
    rules = fields.pop(RULES)
    if rules:   # the item rules are built from all their knobs at once
        fields[BEHAVIOUR]["item_rules"] = rules_for(**rules)
    try:
        timings = Timings(**fields[TIMINGS])
        behaviour = ServerBehaviour(timings=timings, **fields[BEHAVIOUR])
        flight = FlightRules(**fields[FLIGHT])
        config = dataclasses.replace(VehicleConfig(), behaviour=behaviour, flight_rules=flight, **fields[CONFIG])
    except ValueError as exc:   # knobs that do not fit together, e.g. uncapped retries, no timeout
        raise UsageError(f"{path}: {exc}") from None
    return behaviour, config

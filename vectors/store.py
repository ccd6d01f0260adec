"""The vector files on disk: writing a directory of them, reading it back, and checking that
a regeneration gives the same bytes.

Layout of a vectors directory (the package's own is the committed set):
    index.json                          what is here: format, dialect, test key, counts
    messages.jsonl                      one message vector per line (schema/message-vector.schema.json)
    msp.jsonl                           one MSP frame vector per line (vectors/msp.py)
    exchanges/PROFILE/SCENARIO.json     an exchange transcript (schema/exchange.schema.json)
    exchanges/PROFILE/SCENARIO.mcap     the same frames as an MCAP capture (opens in Foxglove)
    exchanges/handover/SCENARIO.*       the handover exchanges (two GCSs), likewise
    schema/*.json                       the two JSON Schemas
Every JSON file is written canonically (sorted keys, no NaN, "\\n" line ends), so the same
seed gives the same bytes.
"""

from __future__ import annotations

import filecmp
import json
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator

from mavconform.reference_impl.errors import UsageError

from . import exchanges, messages, msp
from .dialect_info import DialectInfo
from .schemas import MESSAGE_FORMAT, SCHEMAS

DATA_DIR = Path(__file__).resolve().parent
INDEX = "index.json"
MESSAGES = "messages.jsonl"
EXCHANGES = "exchanges"
SCHEMA_DIR = "schema"


@dataclass
class Generated:
    out: Path
    messages: int
    exchanges: int
    files: int
    seconds: float
    message_seconds: float
    exchange_seconds: float


def generate(out: Path, dialect: DialectInfo, *, seed: int = messages.DEFAULT_SEED) -> Generated:
    """Write every vector of `dialect` into `out` (exchanges only for our own dialect: they are
    our reference GCS and vehicle talking), replacing the data files a previous run wrote."""
    started = time.perf_counter()
    out.mkdir(parents=True, exist_ok=True)
    for old in _data_files(out):
        old.unlink()
    vectors = messages.generate(dialect, seed)
    message_seconds = time.perf_counter() - started
    _write_lines(out / MESSAGES, vectors)
    msp_vectors = msp.generate()
    _write_lines(out / msp.FILE, msp_vectors)
    t1 = time.perf_counter()
    done = []
    if dialect.is_ours:
        for profile in exchanges.PROFILES:
            folder = out / EXCHANGES / profile
            folder.mkdir(parents=True, exist_ok=True)
            for scenario in exchanges.scenarios():
                ex = exchanges.run(scenario, profile, dialect, seed=seed,
                                   mcap_path=folder / f"{scenario.name}.mcap")
                write_transcript(folder / f"{scenario.name}.json", ex.transcript)
                done.append(ex)
        folder = out / EXCHANGES / exchanges.HANDOVER
        folder.mkdir(parents=True, exist_ok=True)
        for hs in exchanges.handover_scenarios():
            ex = exchanges.run_handover(hs, dialect, seed=seed, mcap_path=folder / f"{hs.name}.mcap")
            write_transcript(folder / f"{hs.name}.json", ex.transcript)
            done.append(ex)
    exchange_seconds = time.perf_counter() - t1
    (out / SCHEMA_DIR).mkdir(exist_ok=True)
    for name, schema in SCHEMAS.items():
        _write_json(out / SCHEMA_DIR / name, schema)
    _write_json(out / INDEX, {**_index(dialect, seed, vectors, done), "msp": {
        "file": msp.FILE, "vectors": len(msp_vectors),
        "valid": sum(1 for v in msp_vectors if not v["expected_error"]),
        "invalid": sum(1 for v in msp_vectors if v["expected_error"])}})
    return Generated(out, len(vectors), len(done), len(list(_data_files(out))),
                     time.perf_counter() - started, message_seconds, exchange_seconds)


def _index(dialect: DialectInfo, seed: int, vectors: list[dict[str, Any]],
           done: list[exchanges.Exchange]) -> dict[str, Any]:
    mission = [e for e in done if e.profile != exchanges.HANDOVER]
    handover = [e for e in done if e.profile == exchanges.HANDOVER]
    errors: dict[str, int] = {}
    for v in vectors:
        if v["expected_error"]:
            errors[v["expected_error"]] = errors.get(v["expected_error"], 0) + 1
    return {
        "format": MESSAGE_FORMAT,
        "generator": "mavconform vectors generate (docs/vectors.md)",
        "seed": seed,
        "dialect": {"file": dialect.xml_path.name, "sha256": dialect.xml_sha256,
                    "messages": [m.name for m in dialect.messages],
                    "rule": "every message defined in the dialect file itself (not its includes), by id"},
        "test_key": {"passphrase": messages.TEST_KEY_PASSPHRASE, "hex": messages.TEST_KEY.hex(),
                     "link_id": messages.LINK_ID, "first_timestamp": messages.BASE_TIMESTAMP,
                     "wrong_key_passphrase": messages.WRONG_KEY_PASSPHRASE},
        "messages": {"file": MESSAGES, "vectors": len(vectors),
                     "valid": sum(1 for v in vectors if not v["expected_error"]),
                     "invalid": sum(1 for v in vectors if v["expected_error"]), "by_error": errors},
        "exchanges": {
            "count": len(done),
            "profiles": sorted({e.profile for e in mission}, key=exchanges.PROFILES.index),
            "scenarios": [s.name for s in exchanges.scenarios()] if mission else [],
            "frames": sum(len(e.transcript["events"]) for e in done),
            "handover": {
                "count": len(handover),
                "folder": f"{EXCHANGES}/{exchanges.HANDOVER}",
                "scenarios": [e.scenario.name for e in handover],
                "frames": sum(len(e.transcript["events"]) for e in handover),
            },
        },
    }


def check(directory: Path, dialect: DialectInfo, *, seed: int = messages.DEFAULT_SEED) -> list[str]:
    """Regenerate into a temporary directory and compare with `directory`, byte for byte:
    one line per file that differs, is missing, or is there but would not be generated."""
    with tempfile.TemporaryDirectory() as tmp:
        fresh = Path(tmp)
        generate(fresh, dialect, seed=seed)
        want = {p.relative_to(fresh).as_posix() for p in _data_files(fresh)}
        have = {p.relative_to(directory).as_posix() for p in _data_files(directory)} if directory.is_dir() else set()
        out = [f"{name}: missing (regeneration writes it)" for name in sorted(want - have)]
        out += [f"{name}: stale (regeneration no longer writes it)" for name in sorted(have - want)]
        for name in sorted(want & have):
            if not filecmp.cmp(fresh / name, directory / name, shallow=False):
                out.append(f"{name}: differs from a regeneration")
    return out


def _data_files(directory: Path) -> Iterator[Path]:
    """The files generate() owns in `directory` (never the package's Python files)."""
    for name in (INDEX, MESSAGES, msp.FILE):
        if (directory / name).is_file():
            yield directory / name
    for pattern in (f"{SCHEMA_DIR}/*.json", f"{EXCHANGES}/*/*.json", f"{EXCHANGES}/*/*.mcap"):
        yield from sorted(directory.glob(pattern))


# --- reading -------------------------------------------------------------------------------

@dataclass
class VectorSet:
    directory: Path
    index: dict[str, Any]
    messages: list[dict[str, Any]]
    exchanges: dict[str, Path] = field(default_factory=dict)   # id "profile/scenario" -> transcript path
    msp: list[dict[str, Any]] = field(default_factory=list)


def load(directory: Path) -> VectorSet:
    """A vectors directory; a missing or broken one is a UsageError naming the file."""
    index = _read_json(directory / INDEX)
    if index.get("format") != MESSAGE_FORMAT:
        raise UsageError(f"{directory / INDEX}: not a {MESSAGE_FORMAT} index (format {index.get('format')!r})")
    vectors = _read_lines(directory / MESSAGES, ("id", "hex"), "a vector object with an id and hex")
    found = {f"{p.parent.name}/{p.stem}": p for p in sorted(directory.glob(f"{EXCHANGES}/*/*.json"))}
    msp_path = directory / msp.FILE   # a directory made before MSP, or for a user's dialect, has none
    msp_vectors = (_read_lines(msp_path, ("id", "bytes", "payload"), "an MSP vector object with an id, bytes "
                               "and payload") if msp_path.is_file() else [])
    return VectorSet(directory, index, vectors, found, msp_vectors)


def _read_lines(path: Path, keys: tuple[str, ...], what: str) -> list[dict[str, Any]]:
    """A JSON-lines file of objects with string `keys`; a broken line is a UsageError naming it."""
    out = []
    try:
        with open(path, encoding="utf-8") as fh:
            for n, line in enumerate(fh, 1):
                try:
                    vector = json.loads(line)
                except json.JSONDecodeError as exc:
                    raise UsageError(f"{path}:{n}: not JSON ({exc.msg})") from None
                if not isinstance(vector, dict) or not all(isinstance(vector.get(k), str) for k in keys):
                    raise UsageError(f"{path}:{n}: expected {what}")
                out.append(vector)
    except OSError as exc:
        raise UsageError(f"cannot read {path}: {exc.strerror or exc}") from None
    return out


TRANSCRIPT_KEYS = {"events": list, "peers": dict, "link": dict, "seed": int, "id": str}


def read_transcript(path: Path) -> dict[str, Any]:
    """A transcript with the keys verify and replay read; a hand-edited one missing one is a
    one-line UsageError naming the file and the key, not a KeyError."""
    transcript = _read_json(path)
    if transcript.get("format") != exchanges.FORMAT:
        raise UsageError(f"{path}: not a {exchanges.FORMAT} transcript")
    for key, kind in TRANSCRIPT_KEYS.items():
        if not isinstance(transcript.get(key), kind):
            raise UsageError(f"{path}: {key}: expected a JSON {kind.__name__.replace('dict', 'object').replace('list', 'array')}")
    for n, event in enumerate(transcript["events"]):
        if not isinstance(event, dict) or not all(k in event for k in ("hex", "msg", "from", "to", "t")):
            raise UsageError(f"{path}: events[{n}]: expected an object with hex, msg, from, to and t")
    return transcript


def _read_json(path: Path) -> dict[str, Any]:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise UsageError(f"cannot read {path}: {exc.strerror or exc}") from None
    except json.JSONDecodeError as exc:
        raise UsageError(f"{path}:{exc.lineno}: not JSON ({exc.msg})") from None
    if not isinstance(data, dict):
        raise UsageError(f"{path}: not a JSON object")
    return data


# --- writing -------------------------------------------------------------------------------

def dumps(obj: Any) -> str:
    """Canonical one-line JSON."""
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), allow_nan=False, ensure_ascii=True)


def _write_lines(path: Path, vectors: list[dict[str, Any]]) -> None:
    with open(path, "w", encoding="utf-8", newline="\n") as fh:
        for vec in vectors:
            fh.write(dumps(vec) + "\n")


def _write_json(path: Path, obj: Any) -> None:
    path.write_text(json.dumps(obj, sort_keys=True, indent=2, allow_nan=False) + "\n", encoding="utf-8")


def write_transcript(path: Path, transcript: dict[str, Any]) -> None:
    """Readable and diffable: the header indented, then one event per line."""
    head = {k: v for k, v in transcript.items() if k != "events"}
    text = json.dumps(head, sort_keys=True, indent=2, allow_nan=False)
    events = ",\n".join("    " + dumps(e) for e in transcript["events"])
    text = text[:-2] + ',\n  "events": [\n' + events + "\n  ]\n}\n"
    path.write_text(text, encoding="utf-8")

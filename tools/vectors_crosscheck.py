"""Cross-check mavconform's golden vectors with two MAVLink implementations that are not ours.

    python tools/vectors_crosscheck.py [--impl c,go] [--dir VECTORS] [--dialect XML] [--work DIR]

- `c`: the MAVLink C library pymavlink's mavgen generates from the dialect XML (what PX4 and
  ArduPilot build on), compiled here with gcc (or cc) around tools/vectors_c/harness.c and a
  per-message glue written below (decode with mavlink_msg_X_decode, re-encode with
  mavlink_msg_X_encode_chan).
- `go`: gomavlib (tools/vectors_go, Go module github.com/bluenviron/gomavlib/v3 pinned in
  go.mod/go.sum, fetched from the Go module proxy), with the dialect gomavlib ships
  (upstream development.xml as gomavlib generated it): independent of our XML too, so a
  message or field gomavlib's dialect lacks, or a CRC_EXTRA it computes otherwise, is
  listed by name before any vector is judged.
Each must decode every valid vector (the message vectors and every frame of every exchange
transcript) to the same header and fields, re-encode it to the same bytes, and refuse every
invalid one with its expected error; a mismatch
`vectors/known_deviations.toml` lists is known, any other fails (exit 1). A missing toolchain
fails with the reason (exit 1), it is never skipped. Prints build and verify times.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
C_DIR = ROOT / "tools" / "vectors_c"
GO_DIR = ROOT / "tools" / "vectors_go"
GO_FALLBACK = Path("/usr/local/go/bin/go")    # where the polyglot machines keep Go
IMPLEMENTATIONS = ("c", "go")
NAMES = {"c": "MAVLink C library (mavgen, gcc)", "go": "gomavlib v3.3.5 (Go, its development dialect)"}
BUILD_TIMEOUT = 900     # s: a cold Go build on 2 cores takes about a minute
RUN_TIMEOUT = 300


class ToolchainMissing(Exception):
    """The compiler or toolchain for an implementation is not there: the check fails with this."""


@dataclass
class Built:
    implementation: str
    exe: Path
    seconds: float


@dataclass
class Outcome:
    implementation: str
    build_seconds: float
    verify_seconds: float
    results: dict[str, dict[str, Any]]
    lacks: list[str] = field(default_factory=list)     # gomavlib's dialect against ours


# --- C --------------------------------------------------------------------------------------

def c_glue(dialect: Any) -> str:
    """decode_fields_encode(): one case per message of the dialect, from its XML layout."""
    lines = ["static int decode_fields_encode(const mavlink_message_t *in, uint8_t chan, mavlink_message_t *out) {",
             "    switch (in->msgid) {"]
    for m in dialect.messages:
        low = m.name.lower()
        lines += [f"    case MAVLINK_MSG_ID_{m.name}: {{",
                  f"        mavlink_{low}_t s;",
                  f"        mavlink_msg_{low}_decode(in, &s);"]
        for f in m.fields:
            if f.is_string:
                lines.append(f'        J_S("{f.name}", s.{f.name}, {f.array_length});')
            elif f.array_length:
                lines.append(f'        j_key("{f.name}"); j_open("[");')
                lines.append(f"        for (int k = 0; k < {f.array_length}; k++) {{ j_elem(); {_c_scalar(f, f'{f.name}[k]')}; }}")
                lines.append('        j_close("]");')
            else:
                lines.append(f'        j_key("{f.name}"); {_c_scalar(f, f.name)};')
        lines += [f"        mavlink_msg_{low}_encode_chan(in->sysid, in->compid, chan, out, &s);",
                  "        return 1;", "    }"]
    lines += ["    default:", "        return 0;", "    }", "}", ""]
    return "\n".join(lines)


def _c_scalar(f: Any, expr: str) -> str:
    if f.is_float:
        return f"j_float((double)s.{expr}, {1 if f.type == 'float' else 0})"
    if f.type.startswith("u"):
        return f"j_uint((unsigned long long)s.{expr})"
    return f"j_int((long long)s.{expr})"


def build_c(dialect: Any, work: Path, *, defines: tuple[str, ...] = ()) -> Built:
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        raise ToolchainMissing("no C compiler (gcc or cc) on PATH: install gcc (Debian: apt-get install gcc)")
    started = time.perf_counter()
    include = work / "include"
    gen = subprocess.run([sys.executable, "-m", "pymavlink.tools.mavgen", "--lang", "C", "--wire-protocol", "2.0",
                          "-o", str(include), str(dialect.xml_path)], capture_output=True, text=True, timeout=300)
    stem = dialect.xml_path.stem
    if gen.returncode != 0 or not (include / stem / "mavlink.h").is_file():
        raise RuntimeError(f"pymavlink mavgen --lang C failed for {dialect.xml_path.name}: {gen.stderr.strip()[-400:]}")
    (work / "dialect.h").write_text(f'#include "{stem}/mavlink.h"\n')
    (work / "glue.h").write_text(c_glue(dialect))
    exe = work / "vectors_c"
    done = subprocess.run([cc, "-O1", "-std=c11", "-Wall", "-Wno-address-of-packed-member", "-Wno-unused-function",
                           *(f"-D{d}" for d in defines), "-I", str(include), "-I", str(work),
                           "-o", str(exe), str(C_DIR / "harness.c"), "-lm"],
                          capture_output=True, text=True, timeout=BUILD_TIMEOUT)
    if done.returncode != 0:
        raise RuntimeError(f"the C harness did not compile: {done.stderr.strip()[-800:]}")
    return Built("c", exe, time.perf_counter() - started)


# --- Go -------------------------------------------------------------------------------------

def go_binary() -> str:
    found = shutil.which("go") or (str(GO_FALLBACK) if GO_FALLBACK.is_file() else None)
    if found is None:
        raise ToolchainMissing("no Go toolchain (go on PATH or /usr/local/go/bin/go): gomavlib v3.3.5 needs "
                               "Go >= 1.25 (the polyglot machines have it; elsewhere install it from go.dev)")
    return found


def build_go(work: Path) -> Built:
    go = go_binary()
    started = time.perf_counter()
    exe = work / "vectors_go"
    # go.mod/go.sum pin every module; never upgrade them, nor fetch another Go toolchain
    env = dict(os.environ, GOFLAGS=f"{os.environ.get('GOFLAGS', '')} -mod=readonly".strip(), GOTOOLCHAIN="local")
    done = subprocess.run([go, "build", "-o", str(exe), "."], cwd=GO_DIR, capture_output=True, text=True,
                          timeout=BUILD_TIMEOUT, env=env)
    if done.returncode != 0:
        raise RuntimeError(f"go build in {GO_DIR} failed: {done.stderr.strip()[-800:]}")
    return Built("go", exe, time.perf_counter() - started)


def go_lacks(exe: Path, dialect: Any) -> list[str]:
    """What gomavlib's development dialect lacks or computes otherwise, against `dialect`."""
    done = subprocess.run([str(exe), "--describe"], capture_output=True, text=True, timeout=RUN_TIMEOUT)
    if done.returncode != 0:
        raise RuntimeError(f"vectors_go --describe failed: {done.stderr.strip()[-400:]}")
    theirs = {int(k): v for k, v in json.loads(done.stdout).items()}
    out = []
    for m in dialect.messages:
        other = theirs.get(m.id)
        if other is None:
            out.append(f"{m.name} (id {m.id}): no such message in gomavlib's development dialect")
            continue
        if other["name"] != m.name:
            out.append(f"{m.name} (id {m.id}): gomavlib calls it {other['name']}")
        if other["crc_extra"] != m.crc_extra:
            out.append(f"{m.name}: CRC_EXTRA {other['crc_extra']} in gomavlib, {m.crc_extra} here")
        names = {f["name"]: f for f in other["fields"]}
        for f in m.fields:
            if f.name not in names:
                out.append(f"{m.name}.{f.name}: no such field in gomavlib's development dialect")
            elif names[f.name]["extension"] != f.extension:
                out.append(f"{m.name}.{f.name}: {'an' if names[f.name]['extension'] else 'not an'} extension in gomavlib")
    return out


# --- running and judging --------------------------------------------------------------------

def run(built: Built, vectors: list[dict[str, Any]], key_hex: str) -> tuple[dict[str, dict[str, Any]], float]:
    """Feed every vector to a harness; its results by vector id, and the wall time it took."""
    lines = "".join(f"{v['id']} {int(v['signed'])} {v['hex']}\n" for v in vectors)
    started = time.perf_counter()
    done = subprocess.run([str(built.exe), key_hex], input=lines, capture_output=True, text=True, timeout=RUN_TIMEOUT)
    seconds = time.perf_counter() - started
    if done.returncode != 0:
        raise RuntimeError(f"{built.implementation} harness exited {done.returncode}: {done.stderr.strip()[-400:]}")
    results = {}
    for n, line in enumerate(done.stdout.splitlines(), 1):
        try:
            result = json.loads(line)
        except json.JSONDecodeError as exc:
            raise RuntimeError(f"{built.implementation} harness line {n} is not JSON ({exc.msg}): {line[:200]}") from None
        results[result["id"]] = result
    return results, seconds


def crosscheck(implementation: str, vectors: list[dict[str, Any]], dialect: Any, key_hex: str,
               work: Path) -> Outcome:
    """Build one implementation's harness and run every vector through it."""
    built = build_c(dialect, work) if implementation == "c" else build_go(work)
    results, seconds = run(built, vectors, key_hex)
    lacks = go_lacks(built.exe, dialect) if implementation == "go" else []
    return Outcome(implementation, built.seconds, seconds, results, lacks)


def exchange_vectors(vset: Any) -> list[dict[str, Any]]:
    """Every frame of every exchange transcript as a valid vector (`EXCHANGE#N`): the
    implementations must decode and re-encode what the reference GCS and vehicles really
    sent, not only the message vectors."""
    from mavconform.vectors import store
    out = []
    for exchange_id, path in sorted(vset.exchanges.items()):
        for n, event in enumerate(store.read_transcript(path)["events"]):
            if event["msg"] == "DECODE_ERROR":
                continue
            out.append({"id": f"{exchange_id}#{n}", "signed": False, "signature": None, "hex": event["hex"],
                        "expected_error": None, "msgid": event["msgid"], "message": event["msg"],
                        "fields": event["fields"], "version": event["version"],
                        "header": {"sysid": event["sysid"], "compid": event["compid"], "seq": event["seq"]}})
    return out


def main(argv: list[str] | None = None) -> int:
    from mavconform.reference_impl.errors import UsageError
    from mavconform.vectors import deviations, store, verify
    from mavconform.vectors.dialect_info import load_dialect

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--impl", default=",".join(IMPLEMENTATIONS), help="c, go or c,go (default both)")
    parser.add_argument("--dir", default=str(store.DATA_DIR), help="the vectors directory (default the committed set)")
    parser.add_argument("--dialect", help="the dialect XML the vectors were made from (default ours)")
    parser.add_argument("--work", help="build directory (default a temporary one)")
    args = parser.parse_args(argv)
    chosen = [x.strip() for x in args.impl.split(",") if x.strip()]
    if not chosen or any(x not in IMPLEMENTATIONS for x in chosen):
        parser.error(f"--impl: choose from {', '.join(IMPLEMENTATIONS)}")
    try:
        dialect = load_dialect(args.dialect)
        vset = store.load(Path(args.dir))
        known = deviations.load()
    except UsageError as exc:
        print(f"vectors_crosscheck: error: {exc}", file=sys.stderr)
        return 2
    frames = exchange_vectors(vset)
    vectors = vset.messages + frames
    print(f"{len(vset.messages)} message vectors and {len(frames)} frames of {len(vset.exchanges)} exchanges")
    failed = False
    with tempfile.TemporaryDirectory() as tmp:
        for impl in chosen:
            work = Path(args.work) / impl if args.work else Path(tmp) / impl
            work.mkdir(parents=True, exist_ok=True)
            try:
                outcome = crosscheck(impl, vectors, dialect, vset.index["test_key"]["hex"], work)
            except ToolchainMissing as exc:
                print(f"FAIL {impl}: toolchain missing: {exc}")
                failed = True
                continue
            report = verify.check(impl, vectors, outcome.results, dialect)
            sorted_ = deviations.sort(report, known)
            print(f"{impl}: {NAMES[impl]}: built in {outcome.build_seconds:.1f} s, verified {report.checked} "
                  f"vectors in {outcome.verify_seconds:.3f} s")
            for line in outcome.lacks:
                print(f"  LACKS {line}")
            for dev, count in deviations.counted(sorted_.known):
                print(f"  known ({count} vectors) {dev.vectors}: {dev.observed}")
            for mismatch in sorted_.unexpected:
                print(f"  FAIL {mismatch}")
            for dev in sorted_.unused:
                print(f"  note: known deviation no longer observed: {dev.vectors}: {dev.observed}")
            failed |= bool(sorted_.unexpected)
            print(f"  {report.checked - len({m.vector for m in report.mismatches})} agree, "
                  f"{len(sorted_.known)} known deviations, {len(sorted_.unexpected)} unexpected")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())

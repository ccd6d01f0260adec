"""`mavconform vectors`: golden packet vectors (docs/vectors.md).

    mavconform vectors generate [--out DIR] [--dialect XML] [--seed N] [--check]
    mavconform vectors verify [DIR] [--dialect XML]
    mavconform vectors replay EXCHANGE --target URI [--time-scale S]

`generate` writes the same bytes for the same seed and dialect, so `--check` (regenerate in
a temporary directory and compare) is how CI proves the committed set is current. `verify`
runs every vector through our codec (the independent codecs: tools/vectors_crosscheck.py).
Exit codes: 0 all agree, 1 a vector disagrees (or a replayed target differs or is silent),
2 a usage mistake.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from mavconform.conformance.target_uri import FORMS, parse_target
from mavconform.reference_impl.errors import UsageError
from mavconform.vectors import deviations, messages, msp, replay, store, verify
from mavconform.vectors.dialect_info import load_dialect

from .options import time_scale

DESCRIPTION = """\
Golden packet vectors for codec authors and autopilot teams:
  messages.jsonl   every message of the dialect as MAVLink 2 (extensions zero and set, field
                   edges), MAVLink 1, signed with the published test key, and deliberately
                   broken frames labelled with the error a decoder must report;
  exchanges/       complete exchanges between the reference GCS and the spec, PX4-like and
                   ArduPilot-like vehicles in virtual time, as JSON transcripts and MCAP files.
The committed set is in the package (mavconform/vectors); docs/vectors.md has the format.
"""


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("vectors", help="golden packet vectors: generate, verify, replay",
                       description=DESCRIPTION, formatter_class=argparse.RawDescriptionHelpFormatter)
    vsub = p.add_subparsers(dest="vectors_command", metavar="ACTION", required=True,
                            parser_class=type(p))
    g = vsub.add_parser("generate", help="write the vector files (byte-identical for the same seed)",
                        description="Write messages.jsonl, exchanges/, schema/ and index.json. Exchanges are "
                                    "only made for our own dialect (they are our GCS and vehicle talking).")
    g.add_argument("--out", metavar="DIR", default=str(store.DATA_DIR),
                   help="where to write (default: the package's committed set)")
    g.add_argument("--dialect", metavar="XML", help="make message vectors for every message this dialect XML "
                   "defines (not its includes) instead of ours")
    g.add_argument("--seed", type=int, default=messages.DEFAULT_SEED, help="value seed (default 0)")
    g.add_argument("--check", action="store_true",
                   help="write nothing: regenerate into a temporary directory and compare with --out, "
                        "byte for byte (exit 1 on any difference)")
    g.set_defaults(run=run_generate)

    v = vsub.add_parser("verify", help="decode, re-encode and check every vector with our codec",
                        description="Every message vector: decoded by our codec (FrameDecoder, the test key for "
                                    "signed ones) to its header and fields, re-encoded (FrameEncoder) to its "
                                    "bytes, or refused with its expected error; every exchange frame decoded "
                                    "to its recorded fields and re-encoded to its bytes. Known deviations "
                                    "(vectors/known_deviations.toml) are listed, not failed.")
    v.add_argument("dir", nargs="?", default=str(store.DATA_DIR), metavar="DIR",
                   help="a vectors directory (default: the committed set)")
    v.add_argument("--dialect", metavar="XML", help="the dialect the vectors were made from (default ours)")
    v.set_defaults(run=run_verify)

    r = vsub.add_parser("replay", help="send an exchange's GCS side to a target; report where its replies differ",
                        description=replay.__doc__.split("\n\n", 1)[1],
                        formatter_class=argparse.RawDescriptionHelpFormatter)
    r.add_argument("exchange", metavar="EXCHANGE",
                   help="a transcript file (exchanges/PROFILE/SCENARIO.json) or its id PROFILE/SCENARIO")
    r.add_argument("--target", required=True, metavar="URI", help=f"the target ({FORMS})")
    r.add_argument("--time-scale", type=time_scale, default=1.0, metavar="S",
                   help="UDP targets: stretch the recorded times by S (default 1)")
    r.set_defaults(run=run_replay)


def run_generate(args: argparse.Namespace) -> int:
    dialect = load_dialect(args.dialect)
    out = Path(args.out)
    if args.check:
        problems = store.check(out, dialect, seed=args.seed)
        for line in problems:
            print(f"DIFF {line}")
        print(f"{out}: " + ("identical to a regeneration" if not problems else
                            f"{len(problems)} file(s) differ from a regeneration: run `mavconform vectors "
                            f"generate --out {out}` and commit"))
        return 1 if problems else 0
    if out.exists() and not out.is_dir():
        raise UsageError(f"--out {args.out}: not a directory")
    try:
        done = store.generate(out, dialect, seed=args.seed)
    except OSError as exc:
        raise UsageError(f"--out {args.out}: {exc.strerror or exc}") from None
    rate = done.messages / done.message_seconds if done.message_seconds else float("inf")
    print(f"wrote {done.messages} message vectors and {done.exchanges} exchanges ({done.files} files) to {out} "
          f"in {done.seconds:.2f} s ({rate:,.0f} message vectors/s; exchanges {done.exchange_seconds:.2f} s)")
    return 0


def run_verify(args: argparse.Namespace) -> int:
    dialect = load_dialect(args.dialect)
    vset = store.load(Path(args.dir))
    if vset.index.get("dialect", {}).get("sha256") != dialect.xml_sha256:
        raise UsageError(f"{args.dir}: made from {vset.index.get('dialect', {}).get('file')!r}, not from "
                         f"{dialect.xml_path.name} as it is now: pass --dialect, or regenerate")
    started = time.perf_counter()
    results = {vec["id"]: verify.ours(vec, dialect) for vec in vset.messages}
    report = verify.check("ours", vset.messages, results, dialect)
    seconds = time.perf_counter() - started
    sorted_ = deviations.sort(report, deviations.load())
    for dev, count in deviations.counted(sorted_.known):
        print(f"known ({count} vectors) {dev.vectors}: {dev.observed}")
    for mismatch in sorted_.unexpected:
        print(f"FAIL {mismatch}")
    for dev in sorted_.unused:
        print(f"note: known deviation no longer observed: {dev.vectors}: {dev.observed}")
    frames, exchange_problems = 0, []
    t1 = time.perf_counter()
    for ex_id, path in vset.exchanges.items():
        transcript = store.read_transcript(path)
        frames += len(transcript["events"])
        exchange_problems += [f"{ex_id}: {p}" for p in verify.exchange_frames(transcript, dialect)]
    for line in exchange_problems:
        print(f"FAIL {line}")
    exchange_seconds = time.perf_counter() - t1
    msp_problems = [f"{vec['id']}: {why}" for vec in vset.msp if (why := msp.verify_ours(vec)) is not None]
    for line in msp_problems:
        print(f"FAIL {line}")
    disagree = len({m.vector for m in report.mismatches})
    print(f"ours: {report.checked} message vectors in {seconds:.3f} s: {report.checked - disagree} agree, "
          f"{len(sorted_.known)} known deviations, {len(sorted_.unexpected)} unexpected; "
          f"{len(vset.exchanges)} exchanges, {frames} frames in {exchange_seconds:.3f} s: "
          f"{len(exchange_problems)} disagree; {len(vset.msp)} MSP vectors: {len(msp_problems)} disagree")
    return 1 if sorted_.unexpected or exchange_problems or msp_problems else 0


def run_replay(args: argparse.Namespace) -> int:
    uri = parse_target(args.target)
    path = Path(args.exchange)
    if not path.is_file():
        known = store.load(store.DATA_DIR).exchanges if (store.DATA_DIR / store.INDEX).is_file() else {}
        if args.exchange not in known:
            raise UsageError(f"no exchange {args.exchange!r}: give a transcript file or an id such as "
                             f"spec/upload-mission (`ls {store.DATA_DIR / store.EXCHANGES}/*`)")
        path = known[args.exchange]
    transcript = store.read_transcript(path)
    result = replay.replay(transcript, uri, load_dialect(), scale=args.time_scale)
    print(replay.render(result))
    return 0 if result.ok else 1

"""Regenerate `mavconform_dialect.py` from `mavconform_dialect.xml` with pymavlink's mavgen.

    python -m reference_impl.wire.dialect.regenerate           # rewrite the committed module
    python -m reference_impl.wire.dialect.regenerate --check   # exit 1 if it is out of date

The generated module is committed so that importing the dialect needs neither mavgen nor
lxml; this script is the only way it should change. Schema validation is off for the same
reason (it needs lxml); the XML does validate against pymavlink's mavschema.xsd if you run
mavgen with validation on.

`-m` imports the package, which imports the generated module; if that file is missing or
broken, run this file directly instead (`python reference_impl/wire/dialect/regenerate.py`):
it has no package-relative imports for exactly that reason.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import sys
import tempfile
from pathlib import Path

import pymavlink
from pymavlink.generator import mavgen, mavparse

HERE = Path(__file__).resolve().parent
XML_PATH = HERE / "mavconform_dialect.xml"
PY_PATH = HERE / "mavconform_dialect.py"


def generate(out_dir: Path) -> Path:
    """Run mavgen (Python3, wire protocol 2.0, no validation) into `out_dir`; return the module.

    The output keeps the committed file's basename because mavgen derives `DIALECT` from it.
    Output is byte-for-byte deterministic with pymavlink 2.4.50: the header names the XML by
    basename only and the Python template embeds no date (mavparse records a parse date, but
    only other languages' templates print it), so no post-processing is needed. The guard
    below fails loudly if a future mavgen starts embedding the machine-specific paths.
    """
    target = Path(out_dir) / PY_PATH.name
    opts = mavgen.Opts(str(target), wire_protocol=mavparse.PROTOCOL_2_0, language="Python3", validate=False)
    log = io.StringIO()  # mavgen narrates every step on stdout; keep it for error reports only
    with contextlib.redirect_stdout(log), contextlib.redirect_stderr(log):
        ok = mavgen.mavgen(opts, [str(XML_PATH)])
    if not ok or not target.is_file():
        raise RuntimeError(f"mavgen failed on {XML_PATH}:\n{log.getvalue()}")
    text = target.read_text(encoding="utf-8")
    for path in {str(Path(out_dir)), str(Path(out_dir).resolve()), str(HERE)}:
        if path in text:
            raise RuntimeError(f"mavgen embedded the path {path!r}; strip it here before committing")
    return target


def check() -> str:
    """Regenerate into a temporary directory and compare: "identical", "differs" or "missing"."""
    if not PY_PATH.is_file():
        return "missing"
    with tempfile.TemporaryDirectory() as tmp:
        fresh = generate(Path(tmp)).read_bytes()
    return "identical" if fresh == PY_PATH.read_bytes() else "differs"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="exit 1 if the committed module is out of date")
    args = parser.parse_args(argv)
    if args.check:
        verdict = check()
        if verdict != "identical":
            print(
                f"{PY_PATH.name} is {'missing' if verdict == 'missing' else 'out of date'}: it does not match "
                f"mavgen's output for {XML_PATH.name} (pymavlink {pymavlink.__version__}). "
                "Run: python -m reference_impl.wire.dialect.regenerate",
                file=sys.stderr,
            )
            return 1
        print(f"{PY_PATH.name} is up to date with {XML_PATH.name}")
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        PY_PATH.write_bytes(generate(Path(tmp)).read_bytes())
    print(f"regenerated {PY_PATH}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""``mutrose-cp validate`` on a large output: the delivery family with 12 deliveries (3^12
valid mission decompositions), the first 200,000 of them listed, in JSON (about 90 MB) and in
XML (about 150 MB).

The validator reads the mission decompositions one at a time and checks each independent part
of one once per distinct choice in it (docs/validate.md, "Time and memory"), so its time and
memory grow with the output.  This measures it as the other benchmarks do (a separate process,
bytecode compiled first, wall time and peak resident memory) and prints one JSON row per form;
docs/validate.md keeps the numbers of the last run.

    python benchmarks/validate.py [--deliveries N] [--limit K] [--formats json,xml] [--timeout S]
"""
from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from generate import generate  # noqa: E402
from run import ROOT, compile_bytecode, machine, measure  # noqa: E402

COMMAND = [sys.executable, "-m", "mutrose_cp"]


def _options(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--deliveries", type=int, default=12)
    parser.add_argument("--limit", type=int, default=200_000, help="mission decompositions listed (default 200000)")
    parser.add_argument("--formats", default="json,xml", help="output forms to validate (default json,xml)")
    parser.add_argument("--timeout", type=float, default=600.0, help="time limit of each command (default 600 s)")
    return parser.parse_args(argv)


def _row(mission: list[str], output: Path, form: str, limit: int, timeout: float) -> dict:
    """Decompose into ``output`` (not measured), then measure the validation of it."""
    made = measure([*COMMAND, "decompose", *mission, "-q", "--format", form, "--limit", str(limit), "-o",
                    str(output)], ROOT, timeout)
    if made["status"] != "ok":
        return {"format": form, "decompose": made}
    checked = measure([*COMMAND, "validate", *mission, str(output), "-q", "--json-summary"], ROOT, timeout)
    return {"format": form, "listed": limit, "output_mb": round(output.stat().st_size / 2**20, 1),
            "status": checked["status"], "seconds": checked["seconds"], "peak_mb": checked["peak_mb"]}


def main(argv: list[str] | None = None) -> int:
    args = _options(argv)
    compile_bytecode()
    rows = []
    with tempfile.TemporaryDirectory(prefix="mutrose-validate-") as tmp:
        mission = [str(p) for p in generate("delivery", args.deliveries, Path(tmp))]
        for form in args.formats.split(","):
            row = _row(mission, Path(tmp) / f"output.{form}", form, args.limit, args.timeout)
            rows.append({"family": "delivery", "n": args.deliveries, **row})
            print(json.dumps(rows[-1]), flush=True)
    print(json.dumps({"machine": machine()}))
    return 0 if all(r.get("status") == "ok" for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())

"""The largest mission the benchmarks name: vital signs with 50,000 occupied rooms, `--limit 1`.

One run (it takes minutes and several GB), measured like the ladder's runs (a separate process,
wall time and peak resident memory from its parent), with the size of the streamed output.
Results go to ``benchmarks/results/large.json``, which ``benchmarks/report.py`` adds to the
targets table.

    python benchmarks/large.py [--rooms N] [--timeout SECONDS]
"""
from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from generate import generate  # noqa: E402
from run import RESULTS, ROOT, _digits, compile_bytecode, machine, measure  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rooms", type=int, default=50_000)
    parser.add_argument("--timeout", type=float, default=900.0, help="time limit of the run (default 900 s)")
    args = parser.parse_args(argv)
    compile_bytecode()
    with tempfile.TemporaryDirectory(prefix="mutrose-large-") as tmp:
        hddl, gm, cfg = generate("vital-signs", args.rooms, Path(tmp))
        out = Path(tmp) / "output.json"
        cmd = [sys.executable, "-m", "mutrose_cp", "decompose", str(hddl), str(gm), str(cfg), "-q", "--json-summary",
               "-o", str(out), "--limit", "1"]
        row = {"family": "vital-signs", "n": args.rooms, "algorithm": "cpsat", "runs": 1,
               **measure(cmd, ROOT, args.timeout)}
        row["mission_decompositions"] = _digits(row.get("mission_decompositions"))
        if out.exists():
            row["output_mb"] = round(out.stat().st_size / 2**20, 1)
    result = {"name": "large", "machine": machine(), "date": time.strftime("%Y-%m-%d", time.gmtime()), "rows": [row]}
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / "large.json").write_text(json.dumps(result, indent=1) + "\n", encoding="utf-8")
    print(json.dumps(row))
    return 0 if row["status"] == "ok" else 1


if __name__ == "__main__":
    sys.exit(main())

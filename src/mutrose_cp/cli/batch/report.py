"""What a batch shows: a progress bar while it runs, a summary table at the end (both on stderr).

The bar is drawn only on an interactive terminal, at most ten times a second, like the progress
lines of the other commands.  The time left is estimated from the jobs finished in this run
(the skipped ones took no time).
"""
from __future__ import annotations

import sys
import time
from collections import Counter
from typing import TextIO

from .statuses import OK, STATUSES
from .manifest import Job
from .results import ResultLine

BAR_WIDTH = 24
LISTED_FAILURES = 20  # the summary names at most this many jobs that did not end well
WIDTH = max(len(status) for status in STATUSES)  # of the status column


def _duration(seconds: float) -> str:
    seconds = int(round(seconds))
    if seconds < 60:
        return f"{seconds}s"
    if seconds < 3600:
        return f"{seconds // 60}m{seconds % 60:02d}s"
    return f"{seconds // 3600}h{seconds % 3600 // 60:02d}m"


class Progress:
    """``batch [#######.........] 12/40 jobs, 1 not ok, about 2m10s left``."""

    def __init__(self, total: int, skipped: int, enabled: bool, stream: TextIO | None = None) -> None:
        self.stream = stream or sys.stderr
        self.enabled = enabled and self.stream.isatty()
        self.total, self.skipped = total, skipped
        self.done, self.not_ok = skipped, 0
        self.started = time.monotonic()
        self.last = 0.0

    def finished(self, status: str) -> None:
        self.done += 1
        self.not_ok += status != OK
        self.draw()

    def draw(self) -> None:
        now = time.monotonic()
        if not self.enabled or (now - self.last < 0.1 and self.done < self.total):
            return
        self.last = now
        filled = BAR_WIDTH * self.done // max(self.total, 1)
        ran = self.done - self.skipped
        left = ""
        if 0 < ran and self.done < self.total:
            left = f", about {_duration((now - self.started) / ran * (self.total - self.done))} left"
        self.stream.write(f"\r\033[Kbatch [{'#' * filled}{'.' * (BAR_WIDTH - filled)}] {self.done}/{self.total} jobs, "
                          f"{self.not_ok} not ok{left}")
        if self.done >= self.total:
            self.stream.write("\n")
        self.stream.flush()

    def close(self) -> None:
        if self.enabled and self.done < self.total:
            self.stream.write("\n")
            self.stream.flush()


def summary_table(jobs: list[Job], results: list[ResultLine | None], skipped: int, engine: str,
                  seconds: float) -> str:
    """The closing summary: jobs per status with their time and peak memory, then the jobs that
    did not end well with their problem."""
    finished = [(job, line) for job, line in zip(jobs, results) if line is not None]
    counts = Counter(line.status for _, line in finished)
    ran = len(finished) - skipped
    lines = [f"batch: {len(jobs)} jobs, {ran} run on {engine} in {seconds:.1f} s, {skipped} skipped "
             f"(results present and inputs unchanged)"
             + (f", {len(jobs) - len(finished)} not run" if len(finished) < len(jobs) else ""),
             f"  {'status':<{WIDTH}} {'jobs':>6} {'total s':>10} {'max s':>9} {'max MB':>9}"]
    for status in STATUSES:
        rows = [line for _, line in finished if line.status == status]
        if rows:
            lines.append(f"  {status:<{WIDTH}} {counts[status]:>6} {sum(r.seconds for r in rows):>10.1f} "
                         f"{max(r.seconds for r in rows):>9.1f} {max(r.peak_mb for r in rows):>9.1f}")
    bad = [(job, line) for job, line in finished if line.status != OK]
    if bad:
        lines.append("not ok:")
    for job, line in bad[:LISTED_FAILURES]:
        why = line.problems[0] if line.problems else ""
        code = f" (exit {line.exit_code})" if line.exit_code is not None and line.status != OK else ""
        lines.append(f"  {job.id}: {job}: {line.status}{code}" + (f": {why}" if why else ""))
    if len(bad) > LISTED_FAILURES:
        lines.append(f"  ... and {len(bad) - LISTED_FAILURES} more (see the results file)")
    return "\n".join(lines)

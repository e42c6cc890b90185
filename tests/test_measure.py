"""``run_measured``: a child process's exit status, output, wall time and peak memory, and its
whole process group killed at the time limit (the group part is in test_compare.py)."""
from __future__ import annotations

import sys

from mutrose_cp.measure import run_measured


def test_a_finished_child_gives_its_status_output_and_memory(tmp_path):
    code = "import sys; data = bytearray(64 * 2**20); print('out'); print('err', file=sys.stderr); sys.exit(3)"
    run = run_measured([sys.executable, "-c", code], tmp_path, 60)
    assert not run.timed_out and run.exit_status == 3 and not run.succeeded
    assert run.stdout == "out\n" and run.stderr == "err\n"
    assert run.peak_mb >= 64  # the 64 MB buffer is in the peak


def test_a_child_ended_by_a_signal_has_a_negative_status(tmp_path):
    run = run_measured([sys.executable, "-c", "import os; os.abort()"], tmp_path, 60)
    assert run.exit_status == -6 and not run.timed_out


def test_a_child_over_the_time_limit_is_killed(tmp_path):
    run = run_measured([sys.executable, "-c", "import time; time.sleep(60)"], tmp_path, 1)
    assert run.timed_out and run.exit_status is None

"""Measured child processes (``mutrose_cp.compare.measure``): output, exit status, time limit and cancel
end the child's whole process group."""
from __future__ import annotations

import sys
import threading
import time
from pathlib import Path

import pytest

from mutrose_cp.compare.measure import Cancelled, run_measured

# a child that starts a grandchild in its process group, prints the group id, then waits
FAMILY = [sys.executable, "-c", "import os, subprocess, sys, time; subprocess.Popen(['sleep', '60']); "
          "print(os.getpgid(0), flush=True); time.sleep(60)"]


def _running(pgid: int) -> bool:
    """Whether a process of the group runs (a killed one may stay a zombie for a while)."""
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[2]) == pgid and fields[0] != "Z":  # process group, state
            return True
    return False


def _group_alive(pgid: int) -> bool:
    """Whether the group still runs once the SIGKILL sent to it had time to arrive."""
    for _ in range(100):
        if not _running(pgid):
            return False
        time.sleep(0.05)
    return True


def test_output_and_exit_status_are_collected(tmp_path):
    run = run_measured([sys.executable, "-c", "import sys; print('out'); print('err', file=sys.stderr); sys.exit(3)"],
                       tmp_path, 60)
    assert (run.stdout, run.stderr, run.exit_status, run.timed_out) == ("out\n", "err\n", 3, False)
    assert run.peak_mb > 0 and not run.succeeded


def test_the_time_limit_kills_the_whole_group(tmp_path):
    run = run_measured(FAMILY, tmp_path, 1.0)
    assert run.timed_out and run.exit_status is None
    assert not _group_alive(int(run.stdout.split()[0]))  # the grandchild went with it


def test_cancel_kills_the_group_and_measures_nothing(tmp_path):
    cancel = threading.Event()
    timer = threading.Timer(1.0, cancel.set)
    timer.start()
    out = tmp_path / "pgid"
    command = [*FAMILY[:2], FAMILY[2].replace("print(os.getpgid(0), flush=True)",
                                              f"open({str(out)!r}, 'w').write(str(os.getpgid(0)))")]
    with pytest.raises(Cancelled):
        run_measured(command, tmp_path, 60, cancel=cancel)
    assert not _group_alive(int(out.read_text()))


def test_what_a_run_printed_is_read_once_for_every_caller():
    """The summary is the last stdout line that is a JSON object (a stray "{" line is skipped, not
    a crash); the error lines lose their prefix; an unknown signal still reads as one."""
    from mutrose_cp.compare.measure import Measurement

    run = Measurement(-999, 1.0, 10.0, '{"count": "3"}\n{not json\n[1]\n', "note\nerror: bad goal\nerror: bad task\n")
    assert run.summary == {"count": "3"}
    assert run.errors == ["bad goal", "bad task"]
    assert run.ending == "killed by signal 999"
    assert Measurement(-9, 1.0, 10.0, "", "").ending == "killed by SIGKILL"
    assert Measurement(3, 1.0, 10.0, "", "").ending == "exit status 3" and Measurement(3, 1.0, 10.0, "", "").summary is None


# a parent and its forked child, each holding 150 MB of its own at the same time
TWO_HOLDERS = [sys.executable, "-c", "import os, time; pid = os.fork(); held = b'x' * (150 << 20); time.sleep(1.0); "
               "os._exit(0) if pid == 0 else os.waitpid(pid, 0)"]


@pytest.mark.skipif(not Path("/proc/self/smaps_rollup").exists(), reason="sampling reads /proc/<pid>/smaps_rollup")
def test_the_peak_memory_counts_every_process_of_the_run(tmp_path):
    """The kernel's peak is one process's (about 160 MB here); the run held twice that."""
    run = run_measured(TWO_HOLDERS, tmp_path, 60)
    assert run.succeeded, run.stderr
    assert run.peak_mb > 290

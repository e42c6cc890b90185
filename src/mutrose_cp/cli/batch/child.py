"""The program a batch job runs: ``python -m mutrose_cp.cli.batch.child MEMORY_MB PARENT PEAK_FD COMMAND ARGS...``.

It sets the job's memory limit on itself, then runs the ``mutrose-cp`` command in the same
process (no second interpreter start).  The limit is ``RLIMIT_DATA``, not ``RLIMIT_AS``:

* ``RLIMIT_DATA`` (Linux 4.7 and later) counts the memory the job writes: its heap and its
  private anonymous mappings, which is where a decomposition's data lives;
* ``RLIMIT_AS`` counts address space reserved and never touched as well: every thread's stack
  and every malloc arena of CP-SAT's worker threads (64 MB of address space each), so a job
  using 100 MB can need a limit of 1 GB, a number no user can predict.

It is set here rather than by a ``preexec_fn`` in the parent because the local engine starts its
children from several threads, where ``preexec_fn`` may deadlock.

A job that runs out of memory gets a ``MemoryError`` in Python (reported with exit status
:data:`MEMORY_EXIT`) or a failed allocation in native code (which aborts the process); the parent
classifies both (:func:`mutrose_cp.cli.batch.statuses.classify`).

At its end the child writes its own peak resident memory (``VmHWM``, in kB) to the file
descriptor ``PEAK_FD``.  The parent's ``os.wait4`` cannot tell it: a child's peak counts the
memory of the process that started it, and a Ray worker holds 80 MB before any job runs.

The child also asks the kernel to kill it when its parent dies (Linux ``PR_SET_PDEATHSIG``): a
Ray worker killed by its node, or a driver killed with SIGKILL, leaves no job running on.
"""
from __future__ import annotations

import atexit
import ctypes
import os
import resource
import signal
import sys

MEMORY_EXIT = 99  # the exit status of a job that hit its memory limit in Python code
PR_SET_PDEATHSIG = 1


def limit_memory(megabytes: int) -> None:
    """Cap the data this process may write at ``megabytes`` (0: no limit)."""
    if megabytes > 0:
        limit = megabytes * 1024 * 1024
        resource.setrlimit(resource.RLIMIT_DATA, (limit, limit))


def die_with_parent(parent: int) -> None:
    """Be killed when the parent process ends (Linux only; elsewhere a no-op)."""
    if not sys.platform.startswith("linux"):
        return
    libc = ctypes.CDLL(None, use_errno=True)
    libc.prctl(PR_SET_PDEATHSIG, signal.SIGKILL)
    if os.getppid() != parent:  # the parent ended before the request was made
        os._exit(128 + signal.SIGKILL)


def report_peak(fd: int) -> None:
    """Write this process's peak resident memory (kB) to ``fd``; where there is no ``/proc``,
    nothing (the parent then keeps its own measure)."""
    try:
        with open("/proc/self/status", encoding="ascii") as status:
            peak = next(line.split()[1] for line in status if line.startswith("VmHWM:"))
        os.write(fd, peak.encode())
    except (OSError, StopIteration, IndexError):
        pass


def main(argv: list[str]) -> None:
    megabytes, parent, peak_fd, command = int(argv[0]), int(argv[1]), int(argv[2]), argv[3:]
    die_with_parent(parent)
    limit_memory(megabytes)
    atexit.register(report_peak, peak_fd)
    sys.argv = ["mutrose-cp", *command]
    try:
        from ..program import entry

        entry()
    except MemoryError:
        # print without allocating much: the heap is full
        limit = f"more than --memory-mb {megabytes}" if megabytes else "more than the memory limit it inherited"
        os.write(2, f"error: out of memory: the job needs {limit}\n".encode())
        report_peak(peak_fd)
        os._exit(MEMORY_EXIT)


if __name__ == "__main__":
    main(sys.argv[1:])

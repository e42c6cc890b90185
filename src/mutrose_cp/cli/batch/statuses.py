"""Why a batch job ended: its status, told from how its process ended.

The status says why, because a rerun acts on it: a job that ran out of memory runs again under a
higher ``--memory-mb``, one stopped at its time limit under a higher ``--time-limit``, one
interrupted from outside the batch runs again in any case, and the others are settled.

Running out of memory is told first, whatever the exit status, because a process short of
memory does not say so in one way (:func:`memory_reason`).
"""
from __future__ import annotations

import resource
import signal
from dataclasses import dataclass

from ...compare.measure import Measurement
from .child import MEMORY_EXIT

# statuses of a finished job (docs/batch.md, "Limits and statuses")
OK, FAILED, INVALID, NO_DECOMPOSITION = "ok", "failed", "invalid-input", "no-decomposition"
TIMEOUT, MEMORY, INTERRUPTED, CRASHED = "timeout", "memory", "interrupted", "crashed"
STATUSES = (OK, FAILED, INVALID, NO_DECOMPOSITION, TIMEOUT, MEMORY, INTERRUPTED, CRASHED)
EXIT_STATUSES = {2: INVALID, 3: NO_DECOMPOSITION}  # the command's own exit statuses with a status of their own
INTERRUPT_EXITS = (128 + signal.SIGINT, 128 + signal.SIGTERM)  # the command stopped cleanly on a signal
INTERRUPT_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
# the signals a failed allocation in native code ends a process with: an uncaught std::bad_alloc
# aborts; a stack or a mapping that cannot grow under an address-space limit faults
NATIVE_FAILURE_SIGNALS = (signal.SIGABRT, signal.SIGSEGV, signal.SIGBUS)

# how running out of memory shows in the stderr of a job (compared without case): Python's
# MemoryError; a C++ allocation that failed (OR-Tools: "terminate called after throwing an
# instance of 'std::bad_alloc'"); a system call refused with ENOMEM; the messages of native
# libraries; a thread whose stack cannot be mapped
OUT_OF_MEMORY_SIGNS = ("MemoryError", "bad_alloc", "Cannot allocate memory", "[Errno 12]", "out of memory",
                       "failed to allocate", "memory exhausted", "can't start new thread")
MEMORY_REACHED = 0.9  # a peak this close to the limit means the limit was hit
MB = 1024 * 1024


@dataclass(frozen=True)
class MemoryLimit:
    """The memory limit a job ran under: ``mb`` (0: none), and whether an address-space limit
    (``RLIMIT_AS``, ``ulimit -v``) is among the limits in force.  Address space counts memory
    reserved and never touched, so a job killed under it may have a small resident peak."""

    mb: int = 0
    address_space: bool = False

    @classmethod
    def of(cls, memory_mb: int) -> "MemoryLimit":
        """The limit a job starts under: the batch's ``--memory-mb`` (``RLIMIT_DATA``, set in
        the job's process), or a limit this process has itself and the job inherits
        (``RLIMIT_AS``, ``RLIMIT_DATA``); the lowest of them."""
        inherited = {r: soft // MB for r in (resource.RLIMIT_AS, resource.RLIMIT_DATA)
                     if (soft := resource.getrlimit(r)[0]) != resource.RLIM_INFINITY and soft > 0}
        limits = [m for m in (memory_mb, *inherited.values()) if m > 0]
        return cls(min(limits) if limits else 0, resource.RLIMIT_AS in inherited)

    def under(self) -> str:
        """`` under the limit of N MB``, for messages (nothing without a limit)."""
        if not self.mb:
            return ""
        return f" under the limit of {self.mb} MB" + (" (address space included)" if self.address_space else "")


def classify(run: Measurement, limit: MemoryLimit) -> str:
    """The status of a finished run (see :data:`STATUSES`) under ``limit``."""
    if run.timed_out:
        return TIMEOUT
    if run.exit_status == 0:
        return OK
    if memory_reason(run, limit) is not None:
        return MEMORY
    if run.exit_status in INTERRUPT_EXITS or _signal(run) in INTERRUPT_SIGNALS:
        return INTERRUPTED
    if _abnormal(run):
        return CRASHED
    return EXIT_STATUSES.get(run.exit_status or 0, FAILED)


def _signal(run: Measurement) -> int | None:
    """The signal that ended the run, None if it exited."""
    return -run.exit_status if run.exit_status is not None and run.exit_status < 0 else None


def _abnormal(run: Measurement) -> bool:
    """Whether the run ended other than by the command's own choice: a signal, an uncaught
    exception, or the child's own out-of-memory exit."""
    return _signal(run) is not None or run.exit_status == MEMORY_EXIT or "Traceback (most recent call last)" in run.stderr


def memory_reason(run: Measurement, limit: MemoryLimit) -> str | None:
    """Why the run counts as out of memory, None if it does not.

    A process short of memory does not always say so in one way: Python raises ``MemoryError``
    (the child then exits with :data:`MEMORY_EXIT`), or a C extension fails without saying why
    (``SystemError``) once the ``MemoryError`` is printed; OR-Tools and other native code throw
    ``std::bad_alloc``, which aborts the process; a system call fails with ENOMEM, which a command
    may report as an error of its own; under an address-space limit a stack that cannot grow
    faults (SIGSEGV) with little resident memory; the kernel's out-of-memory killer sends
    SIGKILL (the batch sends it only at the time limit, which is told apart).  So: the child's
    exit status, the signs in its stderr, an unexplained SIGKILL, a native failure signal under
    an address-space limit, or an abnormal end with the peak memory at the limit."""
    under = limit.under()
    if run.exit_status == MEMORY_EXIT:
        return f"ran out of memory{under} (MemoryError)"
    text = run.stderr.lower()
    sign = next((s for s in OUT_OF_MEMORY_SIGNS if s.lower() in text), None)
    if sign is not None:
        return f"ran out of memory{under}: the job reported {sign!r} ({run.ending})"
    killed = _signal(run)
    if killed == signal.SIGKILL:
        return f"ran out of memory{under}: killed by SIGKILL, which the batch did not send (the kernel's " \
               "out-of-memory killer)"
    if limit.address_space and killed in NATIVE_FAILURE_SIGNALS:
        return f"ran out of memory{under}: {run.ending}, as native code does when an allocation fails under an " \
               "address-space limit (ulimit -v)"
    if limit.mb and _abnormal(run) and run.peak_mb >= MEMORY_REACHED * limit.mb:
        return f"ran out of memory{under}: ended abnormally ({run.ending}) with its peak memory at the limit"
    return None


def problems(run: Measurement, status: str, time_limit: float | None, limit: MemoryLimit) -> list[str]:
    """What went wrong, for the results: the command's own ``error:`` lines, or why the batch
    stopped it, or the end of what a crashed process printed."""
    errors = run.errors
    if status == TIMEOUT:
        return [f"stopped at the time limit of {time_limit:g} s"]
    if status == MEMORY:
        return [memory_reason(run, limit) or f"ran out of memory{limit.under()}", *errors]
    if status == INTERRUPTED:
        return [f"interrupted from outside the batch ({run.ending}): it runs again when the batch is run again",
                *errors]
    if status == CRASHED:
        return [run.ending, *run.stderr.strip().splitlines()[-5:]]
    return errors or run.stderr.strip().splitlines()[-5:]  # a failure in its own words, whatever they are

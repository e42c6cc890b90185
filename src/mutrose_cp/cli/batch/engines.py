"""Where the jobs run: a local pool of workers, or a Ray cluster.

Both call :func:`mutrose_cp.cli.batch.job.run_job` for each job, which starts the job's own child
process under its limits, and hand each finished job's outcome back to the driver as it comes
(``report``, always in the driver's main thread).  When the driver is interrupted, the running
jobs are stopped (their children killed) and their outcomes dropped: a job that did not finish
has no result.

**What travels.**  Inputs and outputs go through the file system: a job reads its mission files
and writes its output file itself, by path, atomically, as a single run does.  On a Ray cluster
of several machines every node must therefore see the batch's folder at the same path (a shared
file system, or the same checkout on each node).  Over the network travel only the job's
description (its command line, folder and limits: a few hundred bytes) and its outcome (status,
exit status, time, memory, the command's summary and problems: a few kilobytes).  Mission files
are not copied into the object store: a configuration names its world by a path that the
command resolves from its working folder, so a copy would have to rewrite the mission; and an
output can be gigabytes, which should not pass through the driver.
"""
from __future__ import annotations

import logging
import signal
import socket
import threading
from concurrent.futures import ThreadPoolExecutor, as_completed
from contextlib import contextmanager
from typing import Any, Callable, Iterator, Protocol, Sequence

from ...errors import MissionError
from ...interrupt import Interrupted, current_phase
from .job import JobSpec, Outcome, run_job

Report = Callable[[int, Outcome], None]
RAY_INSTALL = "pip install 'mutrose-cp[ray]'"
CONNECT_SECONDS = 5.0  # how long a cluster's address may take to answer
WAIT_SECONDS = 0.2  # how long the Ray driver waits for a finished job before it looks for an interrupt
JOIN_POLL_SECONDS = 0.05  # how often the main thread looks for an interrupt while Ray joins a cluster


class Engine(Protocol):
    """Where the jobs run: :class:`LocalPool` or :class:`RayCluster`."""

    def describe(self) -> str: ...

    def run(self, specs: Sequence[tuple[int, JobSpec]], report: Report) -> None: ...


class LocalPool:
    """Up to ``workers`` jobs at a time on this machine.  Each job is a child process of its own;
    a thread of the driver waits for each (the work is in the children, so threads are enough)."""

    def __init__(self, workers: int) -> None:
        self.workers = workers

    def describe(self) -> str:
        return f"{self.workers} local worker{'s' if self.workers != 1 else ''}"

    def run(self, specs: Sequence[tuple[int, JobSpec]], report: Report) -> None:
        cancel = threading.Event()
        with ThreadPoolExecutor(self.workers, thread_name_prefix="batch-job") as pool:
            futures = {pool.submit(run_job, spec, cancel): key for key, spec in specs}
            try:
                for future in as_completed(futures):
                    report(futures[future], future.result())
            except BaseException:
                cancel.set()  # every waiting thread kills its child and ends
                pool.shutdown(wait=True, cancel_futures=True)
                raise


def import_ray() -> Any:
    """The ``ray`` module, or a usage error (exit 2) that says how to install it."""
    try:
        import ray
    except ImportError:
        raise MissionError(f"Ray is not installed: install it with  {RAY_INSTALL}  (or pip install ray)",
                           "--ray") from None
    return ray


class RayCluster:
    """The jobs as Ray tasks of one CPU each.  ``address`` None starts a local cluster of
    ``cpus`` CPUs for the batch; ``auto`` or ``HOST:PORT`` joins a running cluster (started with
    ``ray start``), which then schedules the jobs over all its CPUs."""

    def __init__(self, address: str | None, cpus: int) -> None:
        self.address = address
        self.cpus = cpus
        self.ray = import_ray()
        self._described = "Ray"
        self._connected = False

    def describe(self) -> str:
        return self._described

    def run(self, specs: Sequence[tuple[int, JobSpec]], report: Report) -> None:
        ray = self.ray
        try:
            self._start()  # an interrupt here is raised as usual: no job has started
            with _signals_noted() as noted:
                cpus = int(ray.cluster_resources().get("CPU", 0))
                where = "a local cluster" if self.address is None else self.address
                self._described = f"Ray ({where}, {cpus} CPUs)"
                remote = ray.remote(num_cpus=1)(run_job)
                pending = {remote.remote(spec): key for key, spec in specs}
                try:
                    while pending:
                        noted.check()
                        done, _ = ray.wait(list(pending), num_returns=1, timeout=WAIT_SECONDS)
                        for ref in done:
                            report(pending.pop(ref), ray.get(ref))
                except BaseException:
                    self._cancel(list(pending))
                    raise
        finally:
            if self._connected:  # an interrupted join is left to the process's end (see _join)
                ray.shutdown()  # stops a local cluster; leaves a joined one running

    def _start(self) -> None:
        """Start the local cluster, or join the one at ``address``; a cluster that cannot be
        joined is a usage error (exit 2), not a traceback."""
        local = self.address is None
        if self.address is not None:
            _answers(self.address)
        options = dict(address="local" if local else self.address, num_cpus=self.cpus if local else None,
                       include_dashboard=False, log_to_driver=False, logging_level=logging.WARNING)
        try:
            if local:
                self.ray.init(**options)
            else:
                _join(self.ray, options)
            self._connected = True
        except (ConnectionError, ValueError, RuntimeError) as err:
            where = "start a local Ray cluster" if local else f"join the Ray cluster at {self.address}"
            raise MissionError(f"cannot {where}: {err} (a cluster with token authentication needs its token on "
                               "this machine too: ~/.ray/auth_token or RAY_AUTH_TOKEN)", "--ray") from None

    def _cancel(self, refs: list[Any]) -> None:
        """Stop the unfinished tasks: a running one gets a KeyboardInterrupt, on which
        :func:`run_job` kills its child; wait a little for that before disconnecting."""
        for ref in refs:
            self.ray.cancel(ref)
        if refs:
            self.ray.wait(refs, num_returns=len(refs), timeout=10)


def _join(ray: Any, options: dict[str, Any]) -> None:
    """``ray.init(**options)`` for a running cluster, in a thread of its own while the main
    thread waits, so that Ctrl-C (SIGINT) or SIGTERM stops the batch at once.

    Joining waits inside Ray's native code, where Python's signal handlers cannot run: an
    address that accepts connections and never answers (a wrong port, a firewall that holds
    connections) kept the batch deaf to Ctrl-C for the 30 s Ray waits for it.  The main thread
    only waits here, so its handler raises :class:`~mutrose_cp.interrupt.Interrupted` at once.
    The joining thread cannot be stopped; it is a daemon, and an interrupted command ends its
    process right away (``process.exit_process``), the thread with it."""
    failed: list[BaseException] = []
    done = threading.Event()

    def join() -> None:
        try:
            ray.init(**options)
        except BaseException as err:  # noqa: BLE001 - handed to the main thread
            failed.append(err)
        finally:
            done.set()

    quiet = _NotMainThreadWarning()
    logging.getLogger("ray._private.worker").addFilter(quiet)
    try:
        threading.Thread(target=join, name="ray-join", daemon=True).start()
        while not done.wait(JOIN_POLL_SECONDS):
            pass
    finally:
        logging.getLogger("ray._private.worker").removeFilter(quiet)
    if failed:
        raise failed[0]


class _NotMainThreadWarning(logging.Filter):
    """Ray warns that it sets no SIGTERM handler when it is started outside the main thread: the
    batch handles SIGTERM itself, so the warning says nothing to the user."""

    def filter(self, record: logging.LogRecord) -> bool:
        return "not the main thread" not in record.getMessage()


def _answers(address: str) -> None:
    """Refuse at once a ``HOST:PORT`` where nothing listens: Ray itself retries for minutes,
    deaf to Ctrl-C meanwhile.  (``auto`` is looked up by Ray.)"""
    host, sep, port = address.removeprefix("ray://").rpartition(":")
    if not sep or not port.isdigit():
        return
    try:
        socket.create_connection((host, int(port)), timeout=CONNECT_SECONDS).close()
    except OSError as err:
        raise MissionError(f"nothing answers at {address} ({err.strerror or err}): start the cluster with "
                           "ray start --head, or check the address", "--ray") from None


class _NotedSignals:
    """SIGINT and SIGTERM noted while Ray's native code runs, and raised as
    :class:`~mutrose_cp.interrupt.Interrupted` between two of its calls: Ray checks for signals
    inside ``ray.wait`` and turns any exception but ``KeyboardInterrupt`` raised there into a
    ``SystemError``."""

    SIGNALS = (signal.SIGINT, signal.SIGTERM)

    def __init__(self) -> None:
        self.received: list[int] = []

    def _note(self, signum: int, _frame: object) -> None:
        self.received.append(signum)

    def install(self) -> None:
        for signum in self.SIGNALS:
            signal.signal(signum, self._note)

    def check(self) -> None:
        if self.received:
            raise Interrupted(self.received[0], current_phase())


@contextmanager
def _signals_noted() -> Iterator[_NotedSignals]:
    if threading.current_thread() is not threading.main_thread():
        yield _NotedSignals()
        return
    previous = {signum: signal.getsignal(signum) for signum in _NotedSignals.SIGNALS}
    if previous[signal.SIGTERM] is None:  # set outside Python: Ray's native crash handler took SIGTERM over
        previous[signal.SIGTERM] = signal.SIG_DFL
    noted = _NotedSignals()
    noted.install()
    try:
        yield noted
        noted.check()  # a signal during the last wait or the shutdown
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler if handler is not None else signal.SIG_DFL)

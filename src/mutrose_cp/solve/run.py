"""Running CP-SAT to completion, or not at all.

A result is only ever taken from a solve that finished: a status is accepted only where it
proves the search complete (all solutions enumerated, an optimum proven, or infeasibility).
Anything else, a time or memory limit or a stop, raises :class:`IncompleteSolveError`.

The solve runs in a worker thread while the main thread waits in short slices, so a signal is
handled at once (:mod:`mutrose_cp.interrupt`): the solver is asked to stop, the worker is joined,
and the interrupt propagates.  CP-SAT's own SIGINT handler is switched off: it would end the
search early and report the partial enumeration as a normal status.
"""
from __future__ import annotations

import signal
import threading
from typing import Iterable

from ortools.sat.python import cp_model

from ..errors import MissionError


class IncompleteSolveError(MissionError):
    """CP-SAT stopped before it finished; no result is reported (exit status 4)."""

    exit_code = 4


def _stop(solver: cp_model.CpSolver, worker: threading.Thread) -> None:
    """Stop the search and wait for the worker, with further signals held back meanwhile: a
    solver thread still running when the interpreter exits aborts the process.  The stop is
    repeated until the worker ends, in case the search had not started when it was first asked."""
    held = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
    try:
        while worker.is_alive():
            solver.stop_search()
            worker.join(0.05)
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, held)


def run_solver(model: cp_model.CpModel, *, accept: Iterable[cp_model.CpSolverStatus],
               callback: cp_model.CpSolverSolutionCallback | None = None,
               enumerate_all: bool = False, what: str = "a component") -> tuple[cp_model.CpSolver, cp_model.CpSolverStatus]:
    """Solve ``model`` with one worker; returns the solver and a status from ``accept``."""
    solver = cp_model.CpSolver()
    solver.parameters.num_workers = 1
    solver.parameters.catch_sigint_signal = False
    if enumerate_all:
        solver.parameters.enumerate_all_solutions = True
    statuses: list[cp_model.CpSolverStatus] = []
    errors: list[BaseException] = []

    def work() -> None:
        try:
            statuses.append(solver.solve(model, callback) if callback is not None else solver.solve(model))
        except BaseException as exc:  # noqa: BLE001 - handed to the main thread
            errors.append(exc)

    worker = threading.Thread(target=work, name="cp-sat", daemon=True)
    try:
        worker.start()
        while worker.is_alive():
            worker.join(0.05)
    except BaseException:
        _stop(solver, worker)
        raise
    if errors:
        raise errors[0]
    status = statuses[0]
    if status not in set(accept):
        raise IncompleteSolveError(f"CP-SAT did not finish {what} ({solver.status_name(status)}): no result is "
                                   "reported from an unfinished search")
    return solver, status

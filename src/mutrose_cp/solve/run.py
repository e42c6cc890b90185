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

import threading
from typing import Callable, Iterable

from ..errors import MissionError
from ..interrupt import signals_held
from .native import cmh

Status = cmh.CpSolverStatus
OPTIMAL, FEASIBLE, INFEASIBLE = Status.OPTIMAL, Status.FEASIBLE, Status.INFEASIBLE


class IncompleteSolveError(MissionError):
    """CP-SAT stopped before it finished; no result is reported (exit status 4)."""

    exit_code = 4


def _stop(solver: cmh.SolveWrapper, done: threading.Event) -> None:
    """Stop the search and wait for the worker, with further signals held back meanwhile: a
    solver thread still running when the interpreter exits aborts the process.  The stop is
    repeated until the worker ends, in case the search had not started when it was first asked.
    (The worker says when it is done: ``Thread.is_alive`` can turn false while CP-SAT still
    runs in it, once a solution callback has run on that thread.)"""
    with signals_held():
        while not done.is_set():
            solver.stop_search()
            done.wait(0.05)


def _parameters(given: cmh.SatParameters | None, enumerate_all: bool) -> cmh.SatParameters:
    """``given`` (one worker if none), with CP-SAT's own SIGINT handler off."""
    parameters = given if given is not None else cmh.SatParameters()
    if given is None:
        parameters.num_workers = 1
    parameters.catch_sigint_signal = False
    if enumerate_all:
        parameters.enumerate_all_solutions = True
    return parameters


def run_solver(model: cmh.CpModelProto, *, accept: Iterable[Status],
               callback: cmh.SolutionCallback | None = None,
               enumerate_all: bool = False, what: str = "a component",
               parameters: cmh.SatParameters | None = None,
               bound_callback: Callable[[float], None] | None = None) -> cmh.CpSolverResponse:
    """Solve ``model`` (with one worker unless ``parameters`` say otherwise); returns the
    response, whose status is one of ``accept``.  ``bound_callback`` hears of every improvement
    of the objective's proven bound."""
    solver = cmh.SolveWrapper()
    solver.set_parameters(_parameters(parameters, enumerate_all))
    if callback is not None:
        solver.add_solution_callback(callback)
    if bound_callback is not None:
        solver.add_best_bound_callback(bound_callback)
    responses: list[cmh.CpSolverResponse] = []
    errors: list[BaseException] = []
    done = threading.Event()

    def work() -> None:
        try:
            responses.append(solver.solve(model))
        except BaseException as exc:  # noqa: BLE001 - handed to the main thread
            errors.append(exc)
        finally:
            done.set()

    worker = threading.Thread(target=work, name="cp-sat", daemon=True)
    try:
        worker.start()
        while not done.wait(0.05):
            pass
    except BaseException:
        _stop(solver, done)
        raise
    worker.join()
    if errors:
        raise errors[0]
    response = responses[0]
    if response.status not in set(accept):
        raise IncompleteSolveError(f"CP-SAT did not finish {what} ({response.status.name}): no result is "
                                   "reported from an unfinished search")
    return response


class SolutionCollector(cmh.SolutionCallback):
    """Counts the solutions of an enumeration and keeps, for each, which of ``variables``
    (proto indices) are true, as the matching ``ids``; beyond ``cap`` solutions it stops
    keeping them and only counts."""

    def __init__(self, variables: list[int], ids: list[int], keep: bool, cap: int) -> None:
        super().__init__()
        self.variables = variables
        self.ids = ids
        self.keep = keep
        self.cap = cap
        self.solutions: list[frozenset[int]] = []
        self.count = 0

    def OnSolutionCallback(self) -> None:  # noqa: N802 - the helper module's callback name
        self.count += 1
        if self.keep:
            if self.count > self.cap:
                self.keep = False
                self.solutions = []
                return
            self.solutions.append(frozenset(i for v, i in zip(self.variables, self.ids)
                                            if self.SolutionBooleanValue(v)))

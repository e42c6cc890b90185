"""An independent validator of decomposition outputs: the analogue of VAL for PDDL plans.

``validate`` takes the mission inputs and an output file (ours or the original tool's, JSON or
XML) and checks the file against the inputs (docs/validate.md):

* the file: every task entry is a decomposition of a task instance the mission implies, with
  the mission's fields (id, HDDL task, parameters and values, location, robot number, printed
  preconditions and effects, trigger events, actions, Group/Divisible), every such decomposition
  is listed, and the constraints are exactly those the goal model implies;
* every listed mission decomposition: its tasks and choices, the order of its constraints, the
  replay of each task from the state it starts in (method and action preconditions), parallel
  conflicts, creation, achieve and forAll conditions, start values of unknown functions and
  robot numbers.

It uses the readers (``io/``), the data model and the initial world state, and nothing of the
decomposers: the instances (:mod:`.mission_tree`), what each decomposition number stands for
(:mod:`.numbering`), the Task Graph and the constraints (:mod:`.task_graph`,
:mod:`.constraint_rules`) are rebuilt here from the spec's rules, and each task's method tree is
read back from its actions (:mod:`.htn_match`).  So a mistake the decomposers share, or a forged
output, shows up as a violation.
"""
from __future__ import annotations

from .validation import validate
from .report import Report, Violation

__all__ = ["Report", "Violation", "validate"]

"""The typed data model: the frozen values that flow between the stages of the pipeline.

The readers of :mod:`mutrose_cp.io` turn the four mission inputs into these values, and every
later stage only reads them:

* :mod:`~mutrose_cp.model.domain` — the HDDL :class:`Domain` (``io.hddl``);
* :mod:`~mutrose_cp.model.goal_model` — the :class:`GoalModel` and its nodes (``io.goal_model``),
  whose properties hold the values of :mod:`~mutrose_cp.model.expressions` (annotations,
  conditions, ``select`` and ``forAll``; ``io.expressions``);
* :mod:`~mutrose_cp.model.configuration` — the :class:`Configuration` (``io.config``);
* :mod:`~mutrose_cp.model.world` — the :class:`WorldKnowledge` (``io.knowledge``), the
  :class:`InitialState` built from it through the configuration (``mutrose_cp.pipeline.initial_state``), and the
  :class:`Binding` of a goal-model variable during the expansion (``mutrose_cp.pipeline.expansion``,
  read by ``mutrose_cp.pipeline.query`` and ``mutrose_cp.pipeline.conditions``);
* :mod:`~mutrose_cp.model.records` — how a world record (an XML element) reads, as the
  original's PropertyTree reads it;
* :mod:`~mutrose_cp.model.task_graph` — the Task Graph that ``mutrose_cp.pipeline.task_graph_builder`` builds from
  all of the above and the decomposers read (imported from its module: its vertices refer to
  the types of the later stages).

Two condition types exist, one per language: :data:`Condition` is a goal-model condition
(``r.is_clean && ...``), :data:`Precondition` one conjunct of an HDDL precondition.
"""
from __future__ import annotations

from .configuration import Configuration, OutputConfig, SemanticMapping, VarMapping, WorldDbConfig
from .domain import (
    AbstractTask,
    Action,
    Comparison,
    Declaration,
    Domain,
    Literal,
    Method,
    NumericEffect,
    Parameter,
    Precondition,
    Subtask,
    show_precondition,
)
from .expressions import Annotation, AnnotationLeaf, AnnotationOp, Atom, BoolOp, Condition, ForAll, Select
from .goal_model import Context, GMNode, GoalModel, RobotNumber, VarDecl, base_type, is_collection_type
from .world import Binding, GroundLiteral, InitialState, Number, WorldKnowledge

__all__ = [
    "AbstractTask",
    "Action",
    "Annotation",
    "AnnotationLeaf",
    "AnnotationOp",
    "Atom",
    "Binding",
    "BoolOp",
    "Comparison",
    "Condition",
    "Configuration",
    "Context",
    "Declaration",
    "Domain",
    "ForAll",
    "GMNode",
    "GoalModel",
    "GroundLiteral",
    "InitialState",
    "Literal",
    "Method",
    "Number",
    "NumericEffect",
    "OutputConfig",
    "Parameter",
    "Precondition",
    "RobotNumber",
    "Select",
    "SemanticMapping",
    "Subtask",
    "show_precondition",
    "VarDecl",
    "VarMapping",
    "WorldDbConfig",
    "WorldKnowledge",
    "base_type",
    "is_collection_type",
]

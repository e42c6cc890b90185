"""A mission as an HDDL problem (``mutrose-cp export-hddl --problem-out``).

The objects and the initial state are the ones the decomposer builds from the world knowledge
through the configuration's mappings (:mod:`mutrose_cp.pipeline.initial_state`): each object is declared with the
most specific sort it belongs to, the domain's constants are left to the domain, and the
initial state lists the true facts and the function values (the first value of an atom
decides, as in the decomposer).  MutRoSe's world is open (a fact it does not know is assumed to
hold); an HDDL initial state is closed, so such facts are false for a planner.

The task network is the mission's task instances, in goal-model order, when the runtime
annotations make them one total order (only ``;`` joins goals that hold tasks).  A parallel
(``#``, a ``forAll`` over several elements), fallback or OR-decomposed goal over several tasks,
a goal with a context condition, a task that waits for an event, or a parameter bound to a
collection has no form in a single ordered network: :class:`ProblemNotExpressible` says which one and where.  A parameter the
mission leaves unbound (the robots, chosen by the allocator) becomes a variable of the network.
"""
from __future__ import annotations

from ..pipeline.annotation_tree import GOAL, TASK, RatNode
from ..errors import MissionError
from ..model.task_instances import TaskInstance
from ..io.hddl_writer import STANDARD_NAME, ProblemData
from ..pipeline.stages import MissionStages
from ..model import Domain, InitialState
from ..model.domain import Parameter, Subtask


class ProblemNotExpressible(MissionError):
    """The mission has no HDDL problem form (the message says why)."""


def mission_problem(mission: MissionStages) -> tuple[ProblemData, list[str]]:
    """The HDDL problem of ``mission`` and the warnings about it (objects left out)."""
    domain = mission.domain
    order = _total_order(mission.expansion.rat)
    for node in mission.goal_model.nodes:
        if node.context is not None and node.context.kind == "condition":
            raise ProblemNotExpressible(f"goal {node.id} has the context condition {node.context.text}: its tasks "
                                        "run only when it holds, and an HDDL task network has no conditional tasks")
    if not order:
        raise ProblemNotExpressible("the mission has no task instances (no world entity matched its queries): "
                                    "there is no task network to plan for")
    warnings: list[str] = []
    objects = _objects(domain, mission.initial_state, warnings)
    known = {name for name, _ in objects} | {c for c, _ in domain.constants}
    instances = {i.id: i for i in mission.expansion.instances}
    network: list[Subtask] = []
    parameters: list[Parameter] = []
    for instance_id in order:
        step, variables = _step(domain, instances[instance_id], known)
        network.append(step)
        parameters += variables
    facts, values = initial_facts(mission.initial_state, known, warnings)
    comments: tuple[str, ...] = ()
    robot_sorts = domain.robot_sorts
    if parameters and not any(sort in robot_sorts for _, sort in objects):
        comments = ("the world declares no robots: add robot objects (e.g. r1 - robot) before planning",)
    name = f"{domain.name}-mission"
    return ProblemData(name, tuple(objects), facts, values, tuple(parameters), tuple(network), comments), warnings


def _total_order(node: RatNode) -> list[str]:
    """The task instance ids below ``node`` in execution order, when they are totally ordered."""
    if node.kind == TASK:
        return [node.content]
    if node.kind == GOAL:
        return []
    parts = [ids for ids in (_total_order(c) for c in node.children) if ids]
    if len(parts) > 1 and (node.content != ";" or node.or_decomposition):
        goal = node.related_goal or next((c.related_goal for c in node.children if c.related_goal), "?")
        how = ("alternatives of an OR-decomposed goal" if node.or_decomposition
               else "a forAll over several elements, run in parallel" if node.is_forall_dummy
               else "fallback alternatives" if node.content == "FALLBACK" else "run in parallel (#)")
        raise ProblemNotExpressible(
            f"the mission's tasks are not one total order: below goal {goal} the tasks "
            f"{', '.join(p[0] for p in parts)} are {how}; a problem file needs a single ordered network "
            "(write the domain alone, or give the goals a sequential (;) annotation)")
    return [task for ids in parts for task in ids]


def _step(domain: Domain, instance: TaskInstance, known: set[str]) -> tuple[Subtask, list[Parameter]]:
    """The network step of ``instance``: bound parameters as objects, unbound ones as variables."""
    if instance.triggering_events:
        raise ProblemNotExpressible(f"task {instance.id} runs when the event {instance.triggering_events[0]} "
                                    "occurs: an HDDL task network has no events")
    binding = instance.binding
    args: list[str] = []
    variables: list[Parameter] = []
    for parameter in domain.task_by_name[instance.name].parameters:
        value = binding.get(parameter.name)
        if value is None:
            variable = Parameter(f"{parameter.name}_{instance.id}", parameter.type)
            variables.append(variable)
            args.append(variable.name)
        elif isinstance(value, tuple):
            raise ProblemNotExpressible(f"parameter {parameter.name} of task {instance.id} ({instance.name}) is "
                                        f"bound to the collection ({' '.join(value)}): an HDDL task takes one "
                                        "object per parameter")
        elif value not in known:
            raise ProblemNotExpressible(f"parameter {parameter.name} of task {instance.id} ({instance.name}) is "
                                        f"bound to '{value}', which is no object of the world")
        else:
            args.append(value)
    return Subtask(instance.id, instance.name, tuple(args)), variables


def _objects(domain: Domain, state: InitialState, warnings: list[str]) -> list[tuple[str, str]]:
    """(object, most specific sort) for every world object, in the domain's sort order."""
    parent_of = domain.parent_of
    constants = {c for c, _ in domain.constants}
    sorts_of: dict[str, list[str]] = {}
    for sort in [*parent_of, *sorted(set(state.sorts) - set(parent_of))]:
        for name in sorted(state.sorts.get(sort, ())):
            if name not in constants:
                sorts_of.setdefault(name, []).append(sort)
    objects: list[tuple[str, str]] = []
    for name, sorts in sorts_of.items():
        if not STANDARD_NAME.match(name):
            raise ProblemNotExpressible(f"the world object '{name}' has no HDDL name (a letter, then letters, digits, "
                                        "'-' or '_'): rename it in the world knowledge")
        specific = [s for s in sorts if not any(s != o and s in _ancestors(o, parent_of) for o in sorts)]
        if specific[0] not in parent_of and specific[0] != "object":
            warnings.append(f"object {name} is of the sort {specific[0]}, which the domain does not declare: left out")
            continue
        if len(specific) > 1:
            warnings.append(f"object {name} belongs to the unrelated sorts {', '.join(specific)}: declared as "
                            f"{specific[0]}")
        objects.append((name, specific[0]))
    order = {sort: i for i, sort in enumerate(parent_of)}
    return sorted(objects, key=lambda o: (order.get(o[1], len(order)), o[0]))


def _ancestors(sort: str, parent_of: dict[str, str | None]) -> list[str]:
    chain: list[str] = []
    parent = parent_of.get(sort)
    while parent is not None and parent not in chain:
        chain.append(parent)
        parent = parent_of.get(parent)
    return chain


def initial_facts(state: InitialState, known: set[str], warnings: list[str]) -> tuple[
        tuple[tuple[str, tuple[str, ...]], ...], tuple[tuple[str, tuple[str, ...], int | float], ...]]:
    """The true facts and the function values, over declared objects only."""
    facts = tuple((p, args) for (p, args), positive in state.fact_map().items() if positive)
    values = tuple((f, args, v) for (f, args), v in state.value_map().items())
    unknown = sorted(({a for _, args in facts for a in args} | {a for _, args, _ in values for a in args}) - known)
    if unknown:
        warnings.append(f"facts about {', '.join(unknown)}, which are no declared objects, are left out")
    return (tuple(f for f in facts if set(f[1]) <= known),
            tuple(v for v in values if set(v[1]) <= known))

"""Cross-file validation (spec ``config-and-knowledge.md`` §7, ``goal-model.md`` §10).

Each input is checked on its own by its reader; this module checks that they fit together:
goal-model tasks exist in the domain, variable mappings name real parameters of the right
type, semantic mappings match declared predicates, variables are declared before use and only
once, and robot numbers can be inferred.  Every problem is collected, none stops the others.
"""
from __future__ import annotations

from typing import Iterable

from ..errors import Problem, closest
from ..model import (
    AbstractTask,
    Annotation,
    AnnotationOp,
    Configuration,
    Domain,
    GMNode,
    GoalModel,
    SemanticMapping,
    VarMapping,
)
from .query import select_problems


def _where_node(gm: GoalModel, node: GMNode) -> str:
    return f"{gm.source}: {'goal' if node.kind == 'goal' else 'task'} {node.id}"


def _did_you_mean(name: str, candidates: Iterable[str], lead: str = "; did you mean ") -> str:
    """``; did you mean X?`` (or ``lead`` X?) for a close candidate, else nothing."""
    close = closest(name, candidates)
    return f"{lead}{close}?" if close else ""


def check_config(domain: Domain, gm: GoalModel, config: Configuration) -> list[Problem]:
    """§7 of config-and-knowledge.md: var mappings, location types, semantic mappings."""
    controlled = _controlled_variables(gm)
    declared_types = set(controlled.values())
    problems: list[Problem] = []
    gm_tasks = {n.id: n for n in gm.nodes if n.kind == "task"}
    for i, vm in enumerate(config.var_mapping):
        where = config.locate(vm.where or f"var_mapping[{i}]")
        problems += _check_var_mapping(domain, config, vm, where, gm_tasks, controlled)
    problems += _check_location_types(config, declared_types)
    for i, m in enumerate(config.semantic_mapping):
        where = config.locate(m.where or f"semantic_mapping[{i}]")
        problems += _check_semantic_mapping(domain, config, m, where, declared_types)
    return problems


def _controlled_variables(gm: GoalModel) -> dict[str, str]:
    """Every variable some goal controls -> its OCL type (the first declaration, in DFS order)."""
    controlled: dict[str, str] = {}
    for nid in gm.dfs:
        for decl in gm.node(nid).controls:
            controlled.setdefault(decl.name, decl.type)
    return controlled


def _check_var_mapping(domain: Domain, config: Configuration, vm: VarMapping, where: str,
                       gm_tasks: dict[str, GMNode], controlled: dict[str, str]) -> list[Problem]:
    """A var mapping names a goal-model task whose abstract task has the mapped parameters."""
    node = gm_tasks.get(vm.task_id)
    if node is None:
        return [Problem(where, f"task_id {vm.task_id} is not a task of the goal model "
                               f"(tasks: {', '.join(sorted(gm_tasks)) or 'none'})")]
    task = domain.task_by_name.get(node.task_name or "")
    if task is None:
        return [Problem(where, f"Could not find AT {node.task_name} from variable mappings in HDDL AT's: "
                               f"task_id {vm.task_id} is the goal-model task '{node.text}', whose "
                               "name must be an abstract task of the HDDL domain")]
    problems: list[Problem] = []
    for j, (gm_var, hddl_var) in enumerate(vm.pairs):
        if gm_var not in controlled:
            continue  # the original checks only mappings of controlled variables
        problem = _check_mapping_pair(config, task, gm_var, hddl_var, controlled[gm_var], f"{where}.map[{j}]")
        if problem is not None:
            problems.append(problem)
    return problems


def _check_mapping_pair(config: Configuration, task: AbstractTask, gm_var: str, hddl_var: str, ocl: str,
                        where: str) -> Problem | None:
    """The HDDL parameter exists and its type is the one type_mapping gives the variable's OCL type."""
    params = {p.name: p.type for p in task.parameters}
    if hddl_var not in params:
        listing = ", ".join(f"{n} - {t}" for n, t in params.items())
        return Problem(where, f"Could not find variable {hddl_var} in AT "
                              f"{task.name} definition: set hddl_var to one of its parameters "
                              f"({listing}){_did_you_mean(hddl_var, params)}")
    expected = config.type_mapping.get(ocl)
    if expected == params[hddl_var]:
        return None
    fitting = [n for n, t in params.items() if t == expected]
    fix = (f"map {gm_var} to {' or '.join(fitting)}" if fitting else
           f"map {gm_var} to a parameter of HDDL type {expected}" if expected else
           f"add a type_mapping entry for {ocl}")
    return Problem(
        where,
        f"Type error in AT: {task.name}: {gm_var} has OCL type {ocl} mapped to HDDL type "
        f"{expected or '(no type_mapping entry)'}, but {hddl_var} is a {params[hddl_var]}: {fix}",
    )


def _check_location_types(config: Configuration, declared_types: set[str]) -> list[Problem]:
    """Every high-level location type is the type of a variable declared in the goal model."""
    declared_list = ", ".join(sorted(declared_types)) or "none"
    return [Problem(f"{config.source}: location_types",
                    f"High-level location type [{t}] was not declared in the Goal Model: "
                    f"declare a variable of type {t} in the Controls of a goal, or remove "
                    f"{t} from location_types (types declared in the goal model: "
                    f"{declared_list}){_did_you_mean(t, declared_types)}")
            for t in config.location_types if t not in declared_types]


def _check_semantic_mapping(domain: Domain, config: Configuration, m: SemanticMapping, where: str,
                            declared_types: set[str]) -> list[Problem]:
    """A predicate mapping by its type; function mappings are not checked (as in the original)."""
    if m.mapped_type != "predicate":
        return []
    if m.type == "attribute":
        return _check_attribute_mapping(domain, config, m, where, declared_types)
    if m.type in ("ownership", "relationship"):
        return _check_entity_mapping(domain, config, m, where)
    return [Problem(where, f"No mapping type [{m.type}] for semantic mappings. Use attribute, "
                           "ownership or relationship.")]


def _declared_with_sorts(domain: Domain, m: SemanticMapping) -> bool:
    """The domain declares the mapped predicate with exactly the mapping's argument sorts."""
    return any(tuple(p.type for p in d.parameters) == m.arg_sorts for d in domain.predicate_declarations(m.pred))


def _check_attribute_mapping(domain: Domain, config: Configuration, m: SemanticMapping, where: str,
                             declared_types: set[str]) -> list[Problem]:
    """An attribute relates to a goal-model type (or the robot) through a one-argument predicate."""
    if m.relates_to.lower() == "robot":
        return []
    problems: list[Problem] = []
    if m.relates_to not in declared_types:
        declared_list = ", ".join(sorted(declared_types)) or "none"
        problems.append(Problem(where, f"Could not find in GM relation type [{m.relates_to}] declared in "
                                       "semantic mappings: relates_to must be a type declared in the "
                                       f"Controls of a goal ({declared_list})"
                                       f"{_did_you_mean(m.relates_to, declared_types)}"))
    if m.predicate_type is not None and "SEQUENCE" not in m.relates_to.upper():
        problems.append(Problem(where, "Cannot have attribute predicate_type for semantic mapping with "
                                       f"relation type [{m.relates_to}]"))
    if not _declared_with_sorts(domain, m):
        problems.append(Problem(where, _missing_predicate(domain, m.pred, m.arg_sorts)))
    elif len(m.arg_sorts) != 1:
        problems.append(Problem(where, f"Cannot map predicate [{m.pred}] with {len(m.arg_sorts)} arguments "
                                       f"to relation type {m.relates_to}"))
    elif m.arg_sorts[0] != config.type_mapping.get(m.relates_to):
        problems.append(Problem(where, f"Cannot map predicate [{m.pred}] with argument of type "
                                       f"{m.arg_sorts[0]} to relation type {m.relates_to}"
                                       f"{_type_mapping_note(config, m.relates_to)}"))
    return problems


def _check_entity_mapping(domain: Domain, config: Configuration, m: SemanticMapping, where: str) -> list[Problem]:
    """An ownership or relationship maps a two-argument predicate whose sorts are those that
    type_mapping gives its two goal-model types (owned and owner, related and main entity)."""
    if not _declared_with_sorts(domain, m):
        return [Problem(where, _missing_predicate(domain, m.pred, m.arg_sorts))]
    if len(m.arg_sorts) != 2:
        return [Problem(where, f"Wrong number of arguments in predicate of {m.type} type mapping")]
    first, second = (m.owned, m.owner) if m.type == "ownership" else (m.related_entity, m.main_entity)
    names = ("owned", "owner") if m.type == "ownership" else ("related entity", "main entity")
    return [Problem(where, f"Cannot map predicate [{m.pred}] with argument of type {sort} "
                           f"to {label} type {ocl}{_type_mapping_note(config, ocl)}")
            for sort, ocl, label in ((m.arg_sorts[0], first, names[0]), (m.arg_sorts[1], second, names[1]))
            if config.type_mapping.get(ocl) != sort]


def _type_mapping_note(config: Configuration, ocl: str) -> str:
    """Why an argument sort does not fit an OCL type: what the type_mapping says about it."""
    hddl = config.type_mapping.get(ocl)
    if hddl is None:
        return f": type_mapping has no entry for {ocl}; add one"
    return f": type_mapping maps {ocl} to {hddl}, so the argument sort must be {hddl}"


def _missing_predicate(domain: Domain, pred: str, arg_sorts: tuple[str, ...]) -> str:
    message = (f"Could not find predicate [{pred}] declared in semantic mappings with argument sorts "
               f"({' '.join(arg_sorts)})")
    declared = domain.predicate_declarations(pred)
    if declared:
        forms = " or ".join("(" + " ".join([pred, *(p.type for p in d.parameters)]) + ")" for d in declared)
        return f"{message}: the domain declares {forms}; make map.arg_sorts list the same sorts"
    return (f"{message}: declare ({pred} ...) in the :predicates of the HDDL domain or fix map.pred"
            f"{_did_you_mean(pred, (d.name for d in domain.predicates))}")


def check_gm_validity(domain: Domain, gm: GoalModel) -> list[Problem]:
    """§10.3 of goal-model.md: declarations before use, no redeclaration, goal-type rules.

    Nodes are visited depth first, children left to right: a variable is declared for the
    nodes visited after the goal whose Controls declare it."""
    problems: list[Problem] = []
    declared_in: dict[str, str] = {}  # variable -> the goal that controls it
    for nid in gm.dfs:
        node = gm.node(nid)
        where = _where_node(gm, node)
        problems += _check_monitors(node, where, declared_in)
        problems += _check_forall(node, where)
        problems += _check_controls(node, where, declared_in)
        problems += _check_goal(node, where) if node.kind == "goal" else _check_task(domain, node, where)
    return problems


def _check_monitors(node: GMNode, where: str, declared_in: dict[str, str]) -> list[Problem]:
    """A monitored variable must have been declared by a goal visited earlier."""
    problems: list[Problem] = []
    for decl in node.monitors:
        if decl.name not in declared_in:
            close = _did_you_mean(decl.name, declared_in, "Did you mean ")
            fix = ("declare it in the Controls of a goal visited earlier (an ancestor, or a goal to the "
                   "left of one) or fix the name in Monitors")
            problems.append(Problem(where, f"Undeclared variable [{decl.name}] of type [{decl.type}] in goal "
                                           f"{node.id}: {close + ' Otherwise ' if close else ''}{fix}"))
    return problems


def _check_forall(node: GMNode, where: str) -> list[Problem]:
    """A forAll iterates over a monitored variable into a controlled one."""
    if node.forall is None:
        return []
    problems: list[Problem] = []
    if node.forall.iterated not in {d.name for d in node.monitors}:
        problems.append(Problem(where, f"Did not find iterated variable {node.forall.iterated} in "
                                       f"{node.id}'s monitored variables list: add it to the Monitors of "
                                       f"{node.id}"))
    if node.forall.iteration not in {d.name for d in node.controls}:
        problems.append(Problem(where, f"Did not find iteration variable {node.forall.iteration} in "
                                       f"{node.id}'s controlled variables list: add it to the Controls of "
                                       f"{node.id}, e.g. {node.forall.iteration} : <element type>"))
    return problems


def _check_controls(node: GMNode, where: str, declared_in: dict[str, str]) -> list[Problem]:
    """A controlled variable is declared once; a new one is recorded in ``declared_in``."""
    problems: list[Problem] = []
    for decl in node.controls:
        if decl.name in declared_in:
            problems.append(Problem(where, f"Redeclaration of variable [{decl.name}] in goal {node.id}: it is "
                                           f"already controlled by {declared_in[decl.name]}; a variable is "
                                           f"declared once, so rename it here (or list it in Monitors to use "
                                           "the existing one)"))
        else:
            declared_in[decl.name] = node.id
    return problems


def _check_goal(node: GMNode, where: str) -> list[Problem]:
    """The goal-type rules: what a Query, an Achieve and an OR-decomposed goal may contain."""
    problems = _check_query_goal(node, where) if node.goal_type == "Query" else []
    if node.goal_type != "Achieve" and node.achieve_text:
        problems.append(Problem(where, f"Goal of type {node.goal_type} cannot contain an Achieve Condition: "
                                       "set its GoalType to Achieve or remove the AchieveCondition"))
    if node.goal_type != "Query" and node.query is not None:
        problems.append(Problem(where, f"Goal of type {node.goal_type} cannot contain a Queried Property: "
                                       "set its GoalType to Query or remove the QueriedProperty"))
    annotation = node.annotation
    if node.or_decomposed and isinstance(annotation, AnnotationOp) and annotation.op != "#":
        kind = "sequential" if annotation.op == ";" else "fallback"
        problems.append(Problem(where, f"OR decomposed goal cannot have {kind} runtime annotations: the "
                                       "children of an OR refinement are alternatives; drop the "
                                       "annotation or separate them with #"))
    return problems


def _check_query_goal(node: GMNode, where: str) -> list[Problem]:
    """A Query goal has a valid select statement whose result its first controlled variable receives."""
    messages = select_problems(node.query) if node.query is not None else ()
    problems = [Problem(where, f"Invalid query in Goal {node.id}: {message}") for message in messages]
    if not node.controls:
        problems.append(Problem(where, f"No controlled variable was declared for Query goal [{node.id}]: "
                                       "add Controls naming the variable that receives the query result, "
                                       "e.g. rooms : Sequence(Room)"))
    elif node.query is not None and node.query.type != node.controls[0].base_type:
        problems.append(Problem(where, f"Query variable [{node.query.variable}] type [{node.query.type}] "
                                       "is different than the base type of the first controlled "
                                       f"variable [{node.controls[0].name} : {node.controls[0].type}]: "
                                       "the first Controls variable receives the selected records, so "
                                       "their types must agree"))
    elif node.query is None:
        problems.append(Problem(where, f"Missing select statement in Query Goal [{node.id}]: add a "
                                       "QueriedProperty such as world_db->select(r:Room | r.is_clean)"))
    return problems


def _check_task(domain: Domain, node: GMNode, where: str) -> list[Problem]:
    """A goal-model task names an abstract task; one with a robotteam parameter needs a RobotNumber."""
    if node.task_name not in domain.task_by_name:
        return [Problem(where, f"Could not find AT [{node.task_name}] in HDDL Domain definition: "
                               "the name after 'ATk:' must be an abstract task (:task) of the "
                               f"domain ({', '.join(t.name for t in domain.tasks) or 'none'})"
                               f"{_did_you_mean(node.task_name or '', domain.task_by_name)}")]
    if node.robot_number is not None:
        return []
    task = domain.task_by_name[node.task_name]
    teams = [p.name for p in task.parameters if p.type == "robotteam"]
    if not teams:
        return []
    return [Problem(where, "Tasks without RobotNumber attribute cannot have robotteam "
                           f"variable! {node.task_name} has the robotteam parameter "
                           f"{', '.join(teams)}: give the task a RobotNumber such as [2,4]")]


def check_annotations(gm: GoalModel) -> list[Problem]:
    """Annotations should name every child once, in left-to-right diagram order.  The original
    pairs annotation entries with children by position, so a different name or order silently
    changes which subtree is used; these are warnings because real missions contain such typos
    (the reference vital-signs mission writes ``FALLBACK(G4,G17)`` for children G4 and G19)."""
    problems: list[Problem] = []
    for node in gm.nodes:
        if node.kind != "goal" or node.annotation is None or len(node.children) < 2:
            continue
        leaves: list[str] = []

        def collect(a: Annotation) -> None:
            if isinstance(a, AnnotationOp):
                for c in a.children:
                    collect(c)
            else:
                leaves.append(a.name)

        collect(node.annotation)
        child_ids = [gm.node(c).id for c in node.children]
        if leaves != child_ids:
            problems.append(Problem(
                _where_node(gm, node),
                f"runtime annotation lists {', '.join(leaves)} but the children drawn left to right are "
                f"{', '.join(child_ids)}; children are used by position (left to right), so the "
                "annotation is read as if it named them; name every child once, in diagram order",
            ))
    return problems


def cross_check(domain: Domain, gm: GoalModel, config: Configuration) -> list[Problem]:
    """Every cross-file problem of a mission, in the original's order of checking."""
    return check_config(domain, gm, config) + check_gm_validity(domain, gm)

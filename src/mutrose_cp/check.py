"""Cross-file validation (spec ``config-and-knowledge.md`` §7, ``goal-model.md`` §10).

Each input is checked on its own by its reader; this module checks that they fit together:
goal-model tasks exist in the domain, variable mappings name real parameters of the right
type, semantic mappings match declared predicates, variables are declared before use and only
once, and robot numbers can be inferred.  Every problem is collected, none stops the others.
"""
from __future__ import annotations

from .errors import Problem
from .io.config import Configuration
from .io.goal_model import GMNode, GoalModel
from .io.hddl import Domain


def _where_node(gm: GoalModel, node: GMNode) -> str:
    return f"{gm.source}: {'goal' if node.kind == 'goal' else 'task'} {node.id}"


def check_config(domain: Domain, gm: GoalModel, config: Configuration) -> list[Problem]:
    """§7 of config-and-knowledge.md: var mappings, location types, semantic mappings."""
    problems: list[Problem] = []
    src = config.source
    controlled: dict[str, str] = {}
    for nid in gm.dfs:
        for decl in gm.node(nid).controls:
            controlled.setdefault(decl.name, decl.type)
    gm_tasks = {n.id: n for n in gm.nodes if n.kind == "task"}
    for i, vm in enumerate(config.var_mapping):
        where = vm.where or f"{src}: var_mapping[{i}]"
        node = gm_tasks.get(vm.task_id)
        if node is None:
            problems.append(Problem(where, f"task_id {vm.task_id} is not a task of the goal model "
                                           f"(tasks: {', '.join(sorted(gm_tasks)) or 'none'})"))
            continue
        task = domain.task_by_name.get(node.task_name or "")
        if task is None:
            problems.append(Problem(where, f"Could not find AT {node.task_name} from variable mappings in HDDL AT's"))
            continue
        params = {p.name: p.type for p in task.parameters}
        for j, (gm_var, hddl_var) in enumerate(vm.pairs):
            if gm_var not in controlled:
                continue  # the original checks only mappings of controlled variables
            if hddl_var not in params:
                problems.append(Problem(f"{where}.map[{j}]", f"Could not find variable {hddl_var} in AT "
                                        f"{task.name} definition (parameters: {', '.join(params)})"))
                continue
            ocl = controlled[gm_var]
            expected = config.type_mapping.get(ocl)
            if expected != params[hddl_var]:
                problems.append(Problem(
                    f"{where}.map[{j}]",
                    f"Type error in AT: {task.name}: {gm_var} has OCL type {ocl} mapped to HDDL type "
                    f"{expected or '(no type_mapping entry)'}, but {hddl_var} is a {params[hddl_var]}",
                ))
    declared_types = set(controlled.values())
    for t in config.location_types:
        if t not in declared_types:
            problems.append(Problem(f"{src}: location_types",
                                    f"High-level location type [{t}] was not declared in the Goal Model"))
    for i, m in enumerate(config.semantic_mapping):
        where = m.where or f"{src}: semantic_mapping[{i}]"
        if m.mapped_type != "predicate":
            continue
        if m.type == "attribute":
            if m.relates_to.lower() == "robot":
                continue
            if m.relates_to not in declared_types:
                problems.append(Problem(where, f"Could not find in GM relation type [{m.relates_to}] declared in "
                                               "semantic mappings"))
            if m.predicate_type is not None and "SEQUENCE" not in m.relates_to.upper():
                problems.append(Problem(where, "Cannot have attribute predicate_type for semantic mapping with "
                                               f"relation type [{m.relates_to}]"))
            decls = [d for d in domain.predicate_declarations(m.pred)
                     if tuple(p.type for p in d.parameters) == m.arg_sorts]
            if not decls:
                problems.append(Problem(where, f"Could not find predicate [{m.pred}] declared in semantic mappings "
                                               f"with argument sorts ({' '.join(m.arg_sorts)})"))
            elif len(m.arg_sorts) != 1:
                problems.append(Problem(where, f"Cannot map predicate [{m.pred}] with {len(m.arg_sorts)} arguments "
                                               f"to relation type {m.relates_to}"))
            elif m.arg_sorts[0] != config.type_mapping.get(m.relates_to):
                problems.append(Problem(where, f"Cannot map predicate [{m.pred}] with argument of type "
                                               f"{m.arg_sorts[0]} to relation type {m.relates_to}"))
        elif m.type in ("ownership", "relationship"):
            decls = [d for d in domain.predicate_declarations(m.pred)
                     if tuple(p.type for p in d.parameters) == m.arg_sorts]
            if not decls:
                problems.append(Problem(where, f"Could not find predicate [{m.pred}] declared in semantic mappings "
                                               f"with argument sorts ({' '.join(m.arg_sorts)})"))
                continue
            if len(m.arg_sorts) != 2:
                problems.append(Problem(where, f"Wrong number of arguments in predicate of {m.type} type mapping"))
                continue
            first, second = (m.owned, m.owner) if m.type == "ownership" else (m.related_entity, m.main_entity)
            names = ("owned", "owner") if m.type == "ownership" else ("related entity", "main entity")
            for sort, ocl, label in ((m.arg_sorts[0], first, names[0]), (m.arg_sorts[1], second, names[1])):
                if config.type_mapping.get(ocl) != sort:
                    problems.append(Problem(where, f"Cannot map predicate [{m.pred}] with argument of type {sort} "
                                                   f"to {label} type {ocl}"))
        else:
            problems.append(Problem(where, f"No mapping type [{m.type}] for semantic mappings."))
    return problems


def check_gm_validity(domain: Domain, gm: GoalModel) -> list[Problem]:
    """§10.3 of goal-model.md: declarations before use, no redeclaration, goal-type rules."""
    problems: list[Problem] = []
    declared: dict[str, str] = {}
    for nid in gm.dfs:
        node = gm.node(nid)
        where = _where_node(gm, node)
        for decl in node.monitors:
            if decl.name not in declared:
                problems.append(Problem(where, f"Undeclared variable [{decl.name}] of type [{decl.type}] in goal "
                                               f"{node.id}: declare it in the Controls of a goal visited earlier"))
        if node.forall is not None:
            if node.forall.iterated not in {d.name for d in node.monitors}:
                problems.append(Problem(where, f"Did not find iterated variable {node.forall.iterated} in "
                                               f"{node.id}'s monitored variables list"))
            if node.forall.iteration not in {d.name for d in node.controls}:
                problems.append(Problem(where, f"Did not find iteration variable {node.forall.iteration} in "
                                               f"{node.id}'s controlled variables list"))
        for decl in node.controls:
            if decl.name in declared:
                problems.append(Problem(where, f"Redeclaration of variable [{decl.name}] in goal {node.id}"))
            else:
                declared[decl.name] = decl.type
        if node.kind == "goal":
            if node.goal_type == "Query":
                if not node.controls:
                    problems.append(Problem(where, f"No controlled variable was declared for Query goal [{node.id}]"))
                elif node.query is not None and node.query.type != node.controls[0].base_type:
                    problems.append(Problem(where, f"Query variable [{node.query.variable}] type [{node.query.type}] "
                                                   "is different than the base type of the first controlled "
                                                   f"variable [{node.controls[0].name} : {node.controls[0].type}]"))
                elif node.query is None:
                    problems.append(Problem(where, f"Missing select statement in Query Goal [{node.id}]"))
            if node.goal_type != "Achieve" and node.achieve_text:
                problems.append(Problem(where, f"Goal of type {node.goal_type} cannot contain an Achieve Condition"))
            if node.goal_type != "Query" and node.query is not None:
                problems.append(Problem(where, f"Goal of type {node.goal_type} cannot contain a Queried Property"))
            if node.or_decomposed and node.annotation is not None and getattr(node.annotation, "op", "#") != "#":
                kind = "sequential" if node.annotation.op == ";" else "fallback"
                problems.append(Problem(where, f"OR decomposed goal cannot have {kind} runtime annotations"))
        else:
            if node.task_name not in domain.task_by_name:
                problems.append(Problem(where, f"Could not find AT [{node.task_name}] in HDDL Domain definition "
                                               f"(abstract tasks: {', '.join(t.name for t in domain.tasks)})"))
            elif node.robot_number is None:
                task = domain.task_by_name[node.task_name]
                if any(p.type == "robotteam" for p in task.parameters):
                    problems.append(Problem(where, "Tasks without RobotNumber attribute cannot have robotteam "
                                                   "variable! Give the task a RobotNumber such as [2,4]"))
    return problems


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

        def collect(a) -> None:
            if hasattr(a, "children"):
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

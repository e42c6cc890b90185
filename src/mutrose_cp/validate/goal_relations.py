"""How two task decompositions of an output are related by the goal model: the operator under
which they meet (``;``, ``#``, ``FALLBACK`` or an OR goal), the goals above a task and the copy of
each goal a task belongs to (the forAll elements above it, read from its instance number).

Read from the goal model and the task ids alone (annotation entries pair with a goal's children
by position, as in the original); the validator orders effects and groups achieve conditions by
it, next to what the file's constraints say.
"""
from __future__ import annotations

from ..io.decomposition_output import OutputTask
from ..model import Annotation, AnnotationLeaf, GMNode, GoalModel


def _leaves(annotation: Annotation) -> int:
    return 1 if isinstance(annotation, AnnotationLeaf) else sum(_leaves(c) for c in annotation.children)


def lowest_operator(annotation: Annotation, a: int, b: int) -> str | None:
    """The operator of the smallest sub-expression holding leaf positions ``a`` and ``b``."""
    if isinstance(annotation, AnnotationLeaf):
        return None
    start = 0
    for child in annotation.children:
        n = _leaves(child)
        if start <= a < start + n and start <= b < start + n:
            return lowest_operator(child, a - start, b - start)
        start += n
    return annotation.op


Place = tuple[str, tuple[str, ...], int]  # (goal, its copy, position of the child leading down)


class GoalRelations:
    def __init__(self, gm: GoalModel) -> None:
        self.gm = gm
        self.task_path = {n.id: self.ancestors(n) for n in gm.nodes if n.kind == "task"}
        self._above = {t: {g.key for g in path} for t, path in self.task_path.items()}
        self._levels: dict[str, list[tuple[str, int, int]]] = {}
        self._forall_depths: dict[str, int] = {}

    def ancestors(self, node: GMNode) -> list[GMNode]:
        out = []
        cur = node.parent
        while cur is not None:
            n = self.gm.node(cur)
            out.append(n)
            cur = n.parent
        return out

    def branch_tasks(self, key: str) -> list[str]:
        node = self.gm.node(key)
        if node.kind == "task":
            return [node.id]
        return [t for c in node.children for t in self.branch_tasks(c)]

    def below(self, task: OutputTask, goal: GMNode) -> bool:
        above = self._above.get(task.gm_task)
        return above is not None and goal.key in above

    def forall_depth(self, goal: GMNode) -> int:
        """The forAll goals at or above ``goal``: how many leading numbers of an instance id
        tell the copies of ``goal`` apart."""
        depth = self._forall_depths.get(goal.key)
        if depth is None:
            depth = self._forall_depths[goal.key] = sum(1 for n in [goal, *self.ancestors(goal)]
                                                        if n.forall is not None)
        return depth

    def depth_below(self, gm_task: str, goal: GMNode) -> int:
        for d, n in enumerate(self.task_path.get(gm_task, [])):
            if n.key == goal.key:
                return d
        return 0

    # -- meeting ---------------------------------------------------------------------------------
    def relation(self, a: OutputTask, b: OutputTask) -> str:
        """The operator under which two tasks meet: ``;``, ``#``, ``FALLBACK`` or ``OR``."""
        return self.meeting(a, b)[0]

    def sequenced_before(self, a: OutputTask, b: OutputTask) -> bool:
        """Whether ``a`` runs before ``b`` by a ``;`` of the goal model.  The constraints do not
        always say so: a subtree whose constraint list is empty (a one-child operator above a
        single task) gets no constraint with its siblings (semantics.md §6.1), and yet the
        tasks after it see its effects."""
        op, pos_a, pos_b = self.meeting(a, b)
        return op == ";" and pos_a < pos_b

    def meeting(self, a: OutputTask, b: OutputTask) -> tuple[str, int, int]:
        """The operator under which two tasks meet, and the positions in its goal's annotation
        of the children that lead to them (-1, -1 where none): the lowest goal above both, and
        in its annotation the lowest operator over those children.  Instances of different
        forAll elements meet under the forAll's parallel node."""
        if a.gm_task not in self.task_path or b.gm_task not in self.task_path:
            return "#", -1, -1
        up_a = [self.gm.node(a.gm_task)] + self.task_path[a.gm_task]
        up_b = [self.gm.node(b.gm_task)] + self.task_path[b.gm_task]
        keys_b = [n.key for n in up_b]
        depth_a = next(d for d, n in enumerate(up_a) if n.key in keys_b)
        meet = up_a[depth_a]
        common = self.forall_depth(meet)
        if a.instance.split("_")[1:1 + common] != b.instance.split("_")[1:1 + common]:
            return "#", -1, -1  # different elements of a forAll above both
        if depth_a == 0 or keys_b.index(meet.key) == 0:
            return "#", -1, -1
        if meet.or_decomposed:
            return "OR", -1, -1
        if meet.annotation is None:
            return "#", -1, -1
        pos_a = meet.children.index(up_a[depth_a - 1].key)
        pos_b = meet.children.index(up_b[keys_b.index(meet.key) - 1].key)
        return lowest_operator(meet.annotation, pos_a, pos_b) or "#", pos_a, pos_b

    # -- places ----------------------------------------------------------------------------------
    def places(self, task: OutputTask) -> list[Place]:
        """(goal, copy, child position) for every goal above ``task``; the copy of a goal is the
        task's first instance numbers, one per forAll at or above the goal."""
        elements = task.instance.split("_")[1:]
        return [(goal, tuple(elements[:copies]), position) for goal, copies, position in self.levels(task.gm_task)]

    def levels(self, gm_task: str) -> list[tuple[str, int, int]]:
        """(goal, forAlls at or above it, position of the child leading down) for every goal
        above a goal-model task, once per task."""
        levels = self._levels.get(gm_task)
        if levels is None:
            levels = self._levels[gm_task] = []
            path = self.task_path.get(gm_task, [])
            for below, goal in zip([self.gm.node(gm_task), *path] if path else [], path):
                if below.key in goal.children:
                    levels.append((goal.key, self.forall_depth(goal), goal.children.index(below.key)))
        return levels

"""The text of the output's constraints section, a run of constraints at a time.

A large mission has millions of constraints (ten million at 50,000 vital-signs rooms), and
their text is two thirds of its output.  Each is the same text around its two task keys, by
kind and flags.  So a run of stored rows (:meth:`Constraints.runs`) becomes a template once:
the texts between the keys, with a slot for each key.  Filling the template is two C-level
passes (the keys looked up, the pieces joined), where formatting each constraint was a Python
step; and a stamped forAll copy's run is its source's moved, so every copy of a source fills
the same template.
"""
from __future__ import annotations

from array import array
from typing import Callable, Iterator, Sequence

from ..pipeline.constraints import EC, SEQ, Constraint, Constraints, constraint_of_row

RUN_ROWS = 4096  # rows per template: a run of unstamped rows (a whole mission's) is cut in these
_BETWEEN_KEYS = '",\n                "t1": "'
SEPARATOR = ",\n        "  # between the constraints of the section (indent 8)


def constraint_text_parts(c: Constraint) -> tuple[str, str]:
    """The JSON text of a constraint of ``c``'s kind and flags before its first key and after its
    second (FB is written as EC without flags, as the original does)."""
    head = f'{{\n            "type": "{"SEQ" if c.kind == SEQ else "EC"}",\n            "task_instances": {{\n                "t0": "'
    if c.kind == EC:
        return head, f'"\n            }},\n            "group": "{c.group}",\n            "divisible": "{c.divisible}"\n        }}'
    return head, '"\n            }\n        }'


class _RunTemplate:
    """The text of some rows with their keys left out: ``pieces`` holds the text between the
    keys, with a free slot at every odd place, and ``vertices`` the vertex of each slot."""

    __slots__ = ("pieces", "vertices")

    def __init__(self, rows: Iterator[tuple[int, int, int, int]], parts: Callable[[int, int], tuple[str, str]]) -> None:
        pieces: list[str] = []
        vertices = array("i")
        end = ""
        for code, first, second, flags in rows:
            head, tail = parts(code, flags)
            pieces += (end + head, "", _BETWEEN_KEYS, "")
            vertices.append(first)
            vertices.append(second)
            end = tail + SEPARATOR
        pieces.append(end[:-len(SEPARATOR)])
        self.pieces = pieces
        self.vertices = vertices

    def fill(self, key: Callable[[int], str], shift: int) -> str:
        """The rows' text with their vertices moved by ``shift``, named by ``key``."""
        vertices = self.vertices
        self.pieces[1::2] = map(key, map(shift.__add__, vertices) if shift else vertices)
        return "".join(self.pieces)


def constraint_texts(constraints: Sequence[Constraint], key: Callable[[int], str]) -> Iterator[str]:
    """The constraints at indent 8, as texts of one or more constraints joined by
    :data:`SEPARATOR`, in order; ``key`` names a decomposition vertex."""
    stored = constraints if isinstance(constraints, Constraints) else Constraints(constraints)
    around: dict[tuple[int, int], tuple[str, str]] = {}

    def parts(code: int, flags: int) -> tuple[str, str]:
        found = around.get((code, flags))
        if found is None:
            found = around[(code, flags)] = constraint_text_parts(constraint_of_row((code, 0, 0, flags)))
        return found

    templates: dict[tuple[int, int, int], _RunTemplate] = {}
    for source, lo, hi, shift in stored.runs():
        for start in range(lo, hi, RUN_ROWS):
            end = min(hi, start + RUN_ROWS)
            template = templates.get((id(source), start, end))
            if template is None:
                template = _RunTemplate(source.rows(start, end), parts)
                if source is not stored:  # a source's run is filled again for each of its copies
                    templates[(id(source), start, end)] = template
            yield template.fill(key, shift)

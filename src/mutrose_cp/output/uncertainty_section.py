"""The ``mission_decomposition_uncertainty`` section of an output (docs/formats/output.md): for
each listed decomposition, whether it is valid whatever the uncertain facts are, its probability
of being valid, and the fact values it needs; with the facts and the two counts.

The decompositions are judged as the listing is written (:meth:`UncertaintyRecord.listed`
wraps it), so the section costs one pass over what is listed, and follows the listing; the
original's readers read the sections they know and ignore this one.
"""
from __future__ import annotations

from typing import Any, Iterable, Iterator

from ..model.uncertainty import PROBABILITY_DIGITS, value_text
from ..solve.scenarios import ExpandedSpace
from ..solve.uncertain import Judgement, UncertainSpace


def shown_probability(p: float) -> str:
    """A probability as the output writes it: 12 significant digits, so that sums of products
    print the same on every machine."""
    return f"{p:.{PROBABILITY_DIGITS}g}"


class UncertaintyRecord:
    """The listed decompositions' judgements, gathered while they are written."""

    def __init__(self, space: UncertainSpace) -> None:
        self.space = space
        self.judged: list[Judgement] = []

    def listed(self, decompositions: Iterable[list[int]]) -> Iterator[list[int]]:
        """``decompositions``, each judged as it passes."""
        for decomposition in decompositions:
            self.judged.append(self.space.judge(decomposition))
            yield decomposition

    def section(self, standard: bool = False) -> dict[str, Any]:
        """The section: every scalar a string (the original's JSON style), or JSON numbers and
        booleans (``standard``)."""
        def scalar(value: bool | int | float | str) -> Any:
            if standard:
                return value
            return str(value) if not isinstance(value, float) else shown_probability(value)

        facts = []
        for fact in self.space.uncertainty.facts:
            entry: dict[str, Any] = {"fact": fact.text, "entity": fact.entry.entity, "attribute": fact.entry.attribute}
            if fact.numeric:  # its values, with their probabilities when given
                entry["values"] = [v if standard else value_text(v) for v in fact.values]  # to the digit
                if fact.probabilities is not None:
                    entry["probabilities"] = [scalar(p) for p in fact.probabilities]
            elif fact.probabilities is not None:
                entry["probability"] = scalar(fact.probabilities[-1])
            facts.append(entry)
        decompositions = []
        for judged in self.judged:
            item: dict[str, Any] = {"robust": scalar(judged.robust)}
            if judged.probability is not None:
                item["probability"] = scalar(judged.probability)
            item["needs"] = [fact.shown(value) for fact, value in judged.needs]
            decompositions.append(item)
        # counts stay strings in both styles, as mission_decomposition_space's count: they can
        # have more digits than JSON readers hold in a number
        section = {"uncertain_facts": facts, "possible": str(self.space.count(robust=False)),
                   "robust": str(self.space.count(robust=True)), "decompositions": decompositions}
        if isinstance(self.space, ExpandedSpace):  # the world the tasks section was expanded in
            section["world"] = [{"entity": f.entry.entity, "attribute": f.entry.attribute, "value": value_text(v)}
                                for f, v in zip(self.space.uncertainty.expanded, self.space.frame_world.world.values)]
        return section

"""How a count of valid mission decompositions is shown to a person.

Counts are exact big integers (3^10000 has 4772 digits): the summary lines of ``count`` and
``decompose`` and the ``compare`` table show one exactly up to 15 digits, else by its magnitude
(``1.631e4771``).  The exact number is in the JSON summary and the output files.
"""
from __future__ import annotations

SHOWN_DIGITS = 15  # counts up to this many digits are shown exactly


def shown_count(n: int | None, *, digit_count: bool = False) -> str:
    """``n`` exactly up to ``SHOWN_DIGITS`` digits, else its first four digits and its
    exponent; ``digit_count`` adds how many digits the exact number has.  No count (a run
    that did not finish) is ``-``."""
    if n is None:
        return "-"
    digits = str(n)
    if len(digits) <= SHOWN_DIGITS:
        return digits
    magnitude = f"{digits[0]}.{digits[1:4]}e{len(digits) - 1}"
    return f"{magnitude} (exact: {len(digits)} digits)" if digit_count else magnitude

"""The recursion limit of the pipeline's stages, raised for deep goal models."""
from __future__ import annotations

import functools
import sys
from typing import Any, Callable, TypeVar

T = TypeVar("T")
STAGE_RECURSION_LIMIT = 100_000


def deep(stage: Callable[..., T]) -> Callable[..., T]:
    """Run a pipeline stage with a recursion limit for deep goal models.

    The stages recurse once per goal level (up to ``expansion.MAX_GOAL_DEPTH`` levels, a few
    frames each).  Python-to-Python calls need no C stack, so a high limit is safe there; it is
    not raised while inputs are parsed, where C decoders (JSON) recurse on the C stack."""
    @functools.wraps(stage)
    def run(*args: Any, **kwargs: Any) -> T:
        previous = sys.getrecursionlimit()
        sys.setrecursionlimit(max(previous, STAGE_RECURSION_LIMIT))
        try:
            return stage(*args, **kwargs)
        finally:
            sys.setrecursionlimit(previous)

    return run

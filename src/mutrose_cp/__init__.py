"""mutrose-cp: decompose MutRoSe multi-robot missions into task instances, constraints and
valid mission decompositions, with the original exploratory algorithm and a CP-SAT model."""

__version__ = "0.1.0"

"""Decomposition algorithms over the Task Graph: exploratory (baseline) and CP-SAT."""

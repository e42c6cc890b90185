"""The decomposition pipeline: world knowledge to initial state, queries and conditions, the
goal-model expansion, the HTN stage, the Task Graph with its stamped copies, the constraints,
the checks, and the stages computed lazily for a loaded mission (:mod:`.stages`)."""

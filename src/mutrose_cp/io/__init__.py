"""Readers of the four mission inputs: HDDL domain, goal model, configuration, world knowledge."""

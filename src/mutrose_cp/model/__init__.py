"""The data model: what the readers produce and the pipeline stages pass on."""

"""Allow ``python -m mutrose_cp``."""
from .cli.program import entry

entry()

"""Allow ``python -m mutrose_cp``."""
from .cli import entry

entry()

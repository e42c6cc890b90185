"""Allow ``python -m mutrose_cp``."""
import sys

from .cli import main

sys.exit(main())

"""Comparing decomposers: runs measured as child processes, outputs compared by the reference
rules, and the report (``mutrose-cp compare``)."""

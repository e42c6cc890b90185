"""``mutrose-cp batch``: many missions and worlds at once, on one machine or on a Ray cluster.

A batch is a list of jobs; a job is one run of a ``mutrose-cp`` command (``decompose``,
``count``, ``check``, ``validate``, any command the command line knows) on its inputs, with its
options and its output file.  The stages:

* :mod:`.manifest` reads the list (a JSON or CSV manifest, or the ``--each GLOB`` form) and
  checks every job against the command line's own parser before anything runs;
* :mod:`.results` gives each job its input hash and keeps the results file (JSONL), so a batch
  run again skips the jobs whose results are present and whose inputs are unchanged;
* :mod:`.job` runs one job in a child process of its own, under its time and memory limits
  (:mod:`.child` sets the memory limit inside it), and reads its ``--json-summary``;
* :mod:`.engines` runs the jobs: a local pool of workers, or a Ray cluster;
* :mod:`.report` draws the progress bar and the closing summary table;
* :mod:`.command` is the sub-command that ties them together.
"""

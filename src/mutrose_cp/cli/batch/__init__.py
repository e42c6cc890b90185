"""``mutrose-cp batch``: many missions and worlds at once, on one machine or on a Ray cluster.

A batch is a list of jobs; a job is one run of a ``mutrose-cp`` command (``decompose``,
``count``, ``check``, ``validate``, any command the command line knows) on its inputs, with its
options and its output file.  The stages:

* :mod:`.manifest` reads the list (a JSON or CSV manifest, or the ``--each GLOB`` form) and
  checks every job against the command line's own parser (:mod:`.parser`) before anything runs;
* :mod:`.files` finds what each job reads and writes, from the kinds of path its options
  declare, and :mod:`.inputs` reads the inputs without ever waiting on one;
* :mod:`.safety` refuses, before any job runs, what would destroy a file: two jobs writing one
  file, a job writing the manifest or the results file, a results file that is an input;
* :mod:`.plan` settles all of it, with each job's input hash (:mod:`.results`) and the jobs that
  read what others write (:mod:`.chains`);
* :mod:`.journal` keeps the results file (JSONL): locked, appended whole, checked when read, so a
  batch run again skips the jobs whose results are present and whose inputs are unchanged;
* :mod:`.job` runs one job in a child process of its own, under its time and memory limits
  (:mod:`.child` sets the memory limit inside it), says why it ended (:mod:`.statuses`) and
  removes what a killed job left (:mod:`.temporaries`);
* :mod:`.engines` runs the jobs: a local pool of workers, or a Ray cluster;
* :mod:`.report` draws the progress bar and the closing summary table;
* :mod:`.command` is the sub-command that ties them together.
"""

"""The writers: the output file (the builder, Boost-style and standard JSON, XML), its entry
templates and stamped copy blocks, the write-behind thread and the atomic output files, iHTNs,
the console text of the drop-in, the pictures and charts, and the mission as an HDDL problem."""

"""The experiments of docs/results.md and the journal: scripts/results.toml lists every part's
runs, this driver expands them, runs them at most JOBS at a time and prints the tables
(`bash scripts/results.sh PART [JOBS]` builds the programs first, then runs it).

Modules: `templates` (the values and their `{name}` templates), `plan` (a part expanded into
stages of jobs and tables), `steps` (the named steps a part may call), `runner` (runs a plan or
prints it), `__main__` (the command line).
"""

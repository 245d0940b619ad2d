"""The parts of the `lagcomp` command line that are not commands (`lagcomp.cli` holds those).

`models`: which model a command names (a bundled example, a model compiled earlier, a System in a
file or module); `run_inputs`: a run's parameters, initial state and input signals from flags and
files; `outputs`: writing results in the format the file name's suffix names.
"""

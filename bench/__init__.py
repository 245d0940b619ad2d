"""lagcomp's benchmarks: `python -m bench [--quick] [--out FILE]` from the repository root.

Every figure is printed as a ratio against a baseline measured in the same
run (medians of at least 5 repeats, min–max shown), because the machines
this runs on are small and shared: absolute times move by tens of percent
between runs, ratios much less.  Peers (pydy, cython, jitcode, numbalsoda,
heyoka: the ``bench`` extra) are used when installed and reported as
skipped otherwise; nothing is installed here.

The older single-purpose scripts (bench_compile, bench_run, bench_sweep,
bench_collocation) still run on their own; the entry point reuses them.
"""

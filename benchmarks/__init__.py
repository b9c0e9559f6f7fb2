"""amble's benchmark suite, run on demand (not part of the test run): ``python -m benchmarks``.

Modules: :mod:`benchmarks.bench_derive` (derive + compile an n-link chain), :mod:`benchmarks.bench_walk`
(compass-gait walking speed and accuracy), :mod:`benchmarks.bench_startup` (command-line start-up),
and, if present, ``benchmarks.bench_sweep``. The peers measured beside amble live in
:mod:`benchmarks.peers`.
"""

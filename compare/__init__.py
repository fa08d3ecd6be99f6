"""xval's compare layer. One BLAS thread unless the caller chose otherwise: the frequency
leaves' eigen-solves are small (a few hundred unknowns at most) and threaded BLAS on a 2-core
machine ran them many times slower (fem blade 1.31 s against 0.15 s, Exudyn 5.1 s against
0.10 s, measured with the frequency bench); campaign workers inherit the setting. It takes effect
only where numpy is not loaded yet (the `xval` command, a fresh interpreter)."""
import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

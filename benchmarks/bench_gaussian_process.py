#!/usr/bin/python3
"""adaptseg GaussianProcess vs scikit-learn GaussianProcessRegressor, same data, one run.

    /usr/bin/python3 benchmarks/bench_gaussian_process.py [LABEL=]<path/to/bench_gaussian_process> ... \
        [--sizes 50 200 1000 2000] [--dims 1 2] [--restarts 1] [--queries 10000]

Several binaries (e.g. builds with different compiler flags) can be given, each optionally
labelled: every one runs on the same data and gets its own row next to the same sklearn run.

For every (n, D) it generates one data set (numpy, fixed seed), times scikit-learn in this
process, runs the C++ binary on the same data (written to a temporary file), and prints a
markdown table. Model on both sides: C(sf2) * RBF(l) + WhiteKernel(sn2), alpha = 0,
normalize_y = True, same bounds, same initial hyperparameters, same number of optimiser
restarts (the restart points themselves are each library's own pseudo-random draws).
D = 1: isotropic length scale; D = 2: one length scale per dimension (ARD).

Timed, median over `reps` repetitions (reps = 5 for n <= 200, else 1):
  fit      : hyperparameter optimisation with restarts + final factorisation;
  predict  : mean and (noisy) standard deviation / variance at `queries` points;
  update   : adaptseg add_observation at n (O(n^2) Cholesky extension; median of >= 5), vs. scikit-learn
             refitting n + 1 points with the fitted kernel and optimizer=None (it has no
             online update).
LML columns: the fitted log marginal likelihood (of the normalised targets) of each library.
"""

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
import warnings

import numpy as np
import sklearn
from sklearn.exceptions import ConvergenceWarning
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel

from bench_common import cpu_model

BOUNDS = {"sf2": (1e-5, 1e5), "ls": (1e-5, 1e5), "sn2": (1e-5, 1e5)}
INIT = {"sf2": 1.0, "ls": 1.0, "sn2": 0.1}


def make_data(n, d, m, seed):
    rng = np.random.default_rng(seed)
    x = rng.uniform(0.0, 5.0, size=(n, d))
    f = np.sin(3.0 * x[:, 0])
    if d > 1:
        f = f + 0.5 * np.cos(2.0 * x[:, 1])
    y = 2.0 + f + 0.1 * rng.standard_normal(n)
    xq = rng.uniform(0.0, 5.0, size=(m, d))
    x_new = rng.uniform(0.0, 5.0, size=d)
    y_new = 2.0 + np.sin(3.0 * x_new[0]) + 0.1 * rng.standard_normal()
    return x, y, xq, x_new, y_new


def sklearn_kernel(d):
    ls = INIT["ls"] if d == 1 else np.full(d, INIT["ls"])
    return ConstantKernel(INIT["sf2"], constant_value_bounds=BOUNDS["sf2"]) * RBF(
        ls, length_scale_bounds=BOUNDS["ls"]
    ) + WhiteKernel(INIT["sn2"], noise_level_bounds=BOUNDS["sn2"])


def time_sklearn(x, y, xq, x_new, y_new, restarts, reps):
    fit_t, pred_t, upd_t = [], [], []
    gp = None
    for _ in range(reps):
        gp = GaussianProcessRegressor(
            kernel=sklearn_kernel(x.shape[1]), alpha=0.0, normalize_y=True,
            n_restarts_optimizer=restarts, random_state=0)
        t0 = time.perf_counter()
        gp.fit(x, y)
        fit_t.append(time.perf_counter() - t0)
    for _ in range(reps):
        t0 = time.perf_counter()
        gp.predict(xq, return_std=True)
        pred_t.append(time.perf_counter() - t0)
    x1 = np.vstack([x, x_new])
    y1 = np.append(y, y_new)
    for _ in range(max(reps, 3) if x.shape[0] <= 1000 else 1):
        refit = GaussianProcessRegressor(kernel=gp.kernel_, alpha=0.0, normalize_y=True, optimizer=None)
        t0 = time.perf_counter()
        refit.fit(x1, y1)
        upd_t.append(time.perf_counter() - t0)
    return (statistics.median(fit_t), statistics.median(pred_t), statistics.median(upd_t),
            gp.log_marginal_likelihood_value_, gp.kernel_.theta)


def run_cpp(binary, x, y, xq, x_new, y_new, restarts, reps):
    n, d = x.shape
    with tempfile.NamedTemporaryFile("w", suffix=".txt", delete=False) as f:
        path = f.name
        f.write("%d %d %d %d %d 1\n" % (n, d, xq.shape[0], reps, restarts))
        f.write("bounds %r %r %r %r %r %r\n" % (*BOUNDS["sf2"], *BOUNDS["ls"], *BOUNDS["sn2"]))
        f.write("init %r %r %r\n" % (INIT["sf2"], INIT["ls"], INIT["sn2"]))
        for xi, yi in zip(x, y):
            f.write(" ".join(repr(float(v)) for v in xi) + " %r\n" % float(yi))
        for xi in xq:
            f.write(" ".join(repr(float(v)) for v in xi) + "\n")
        f.write(" ".join(repr(float(v)) for v in x_new) + " %r\n" % float(y_new))
    try:
        out = subprocess.run([binary, path], check=True, capture_output=True, text=True).stdout
    finally:
        os.unlink(path)
    return json.loads(out)


def blas_description():
    try:
        from threadpoolctl import threadpool_info
        info = threadpool_info()
    except ImportError:
        return "threadpoolctl not available"
    blas = [i for i in info if i.get("user_api") == "blas"]
    others = ["%s (%s, %s threads)" % (i.get("internal_api"), os.path.basename(i.get("filepath", "")),
                                       i.get("num_threads")) for i in info]
    if not blas:
        return ("threadpoolctl finds no BLAS pool: numpy/scipy use an unmanaged BLAS "
                "(here: the reference netlib libblas3, single-threaded); pools: " + ", ".join(others))
    return ", ".join(others)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("binary", nargs="+", help="[LABEL=]path to a bench_gaussian_process executable")
    ap.add_argument("--sizes", type=int, nargs="+", default=[50, 200, 1000, 2000])
    ap.add_argument("--dims", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--restarts", type=int, default=1)
    ap.add_argument("--queries", type=int, default=10000)
    args = ap.parse_args()
    warnings.filterwarnings("ignore", category=ConvergenceWarning)

    print("scikit-learn %s, numpy %s, Python %s" % (sklearn.__version__, np.__version__, platform.python_version()))
    print("CPU: %s, %d logical cores; OPENBLAS_CORETYPE=%s, OMP_NUM_THREADS=%s" % (
        cpu_model(), os.cpu_count(), os.environ.get("OPENBLAS_CORETYPE", "(unset)"),
        os.environ.get("OMP_NUM_THREADS", "(unset)")))
    print("BLAS: " + blas_description())
    print("restarts: %d, queries: %d, reps: 5 for n <= 200 else 1 (median)" % (args.restarts, args.queries))
    print()
    binaries = []
    for b in args.binary:
        label, _, path = b.rpartition("=")
        binaries.append((label or "adaptseg", path))
    print("| n | D | build | fit sklearn [s] | fit adaptseg [s] | fit ratio | predict sklearn [s] "
          "| predict adaptseg [s] | predict ratio | update sklearn refit [ms] | update adaptseg [ms] "
          "| LML sklearn | LML adaptseg |")
    print("|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for n in args.sizes:
        for d in args.dims:
            reps = 5 if n <= 200 else 1
            x, y, xq, x_new, y_new = make_data(n, d, args.queries, seed=1000 * n + d)
            sk_fit, sk_pred, sk_upd, sk_lml, _ = time_sklearn(x, y, xq, x_new, y_new, args.restarts, reps)
            for label, path in binaries:
                cpp = run_cpp(path, x, y, xq, x_new, y_new, args.restarts, reps)
                print("| %d | %d | %s | %.4g | %.4g | %.1fx | %.4g | %.4g | %.1fx | %.3g | %.3g | %.6f | %.6f |" % (
                    n, d, label, sk_fit, cpp["fit_s"], sk_fit / cpp["fit_s"], sk_pred, cpp["predict_s"],
                    sk_pred / cpp["predict_s"], 1e3 * sk_upd, 1e3 * cpp["update_s"], sk_lml, cpp["lml"]))
                sys.stdout.flush()


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""Time OpenCV's exact Euclidean distance transform on the bitmaps written by
ct_bench_ddt (bench/bench_ddt.cpp), for the per-pixel ratio it prints.

Usage: bench_ddt_opencv.py [--threads N] [--reps R] FILE.pgm ...
       bench_ddt_opencv.py --serve

A bitmap has 255 at feature pixels.  cv2.distanceTransform measures the
distance to the nearest ZERO pixel, so the input is inverted (features -> 0).
Mode: DIST_L2 with DIST_MASK_PRECISE (exact, Felzenszwalb-Huttenlocher).

With files, for each prints
    RESULT <file> <ns/pixel, 1 thread> <ns/pixel, N threads> <max |ours - cv|>
where the last field compares with FILE.dt.f32 (our unconstrained Euclidean
DT, float32, written by the bench) when present, else -1.

--serve: ct_bench_ddt's coprocess, so that OpenCV and our transform are timed
in alternating rounds of one run (this machine's speed drifts by tens of
percent over seconds; separate runs are not comparable).  Reads commands on
stdin, one per line, and answers one line each:
    T <file> <reps> <threads>  ->  T <best ns/pixel over reps>
    D <file>                   ->  D <max |ours - cv| in px, or -1>
An empty line or end of input ends it.
Requires python3-opencv (Debian: apt-get install -y python3-opencv).
"""
import argparse
import os
import sys
import time

import numpy as np

try:
    import cv2
except ImportError:
    sys.stderr.write("python3-opencv missing: apt-get install -y python3-opencv\n")
    sys.exit(3)

_loaded = {}


def load(path):
    """The inverted bitmap (features -> 0), cached."""
    if path not in _loaded:
        img = cv2.imread(path, cv2.IMREAD_UNCHANGED)
        if img is None:
            raise IOError("cannot read %s" % path)
        _loaded[path] = np.where(img > 0, 0, 1).astype(np.uint8)
    return _loaded[path]


def run(src):
    return cv2.distanceTransform(src, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)


def best_ns_per_px(path, reps, threads):
    src = load(path)
    cv2.setNumThreads(threads)
    best = float("inf")
    for _ in range(reps):
        t0 = time.perf_counter()
        run(src)
        best = min(best, time.perf_counter() - t0)
    return best * 1e9 / src.size


def max_diff(path):
    src = load(path)
    ours = os.path.splitext(path)[0] + ".dt.f32"
    if not os.path.exists(ours) or src.min() != 0:  # cv2 has no "no feature" value
        return -1.0
    d = np.fromfile(ours, dtype=np.float32).reshape(src.shape)
    return float(np.max(np.abs(d.astype(np.float64) - run(src).astype(np.float64))))


def serve():
    print("opencv %s" % cv2.__version__, flush=True)
    for line in sys.stdin:
        w = line.split()
        if not w:
            break
        try:
            if w[0] == "T" and len(w) == 4:
                print("T %.4f" % best_ns_per_px(w[1], int(w[2]), int(w[3])), flush=True)
            elif w[0] == "D" and len(w) == 2:
                print("D %.6g" % max_diff(w[1]), flush=True)
            else:
                print("E bad command", flush=True)
        except Exception as e:  # one line back, never a hang
            print("E %s" % str(e).replace("\n", " "), flush=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--reps", type=int, default=0, help="0: by size")
    ap.add_argument("--serve", action="store_true")
    ap.add_argument("files", nargs="*")
    a = ap.parse_args()
    if a.serve:
        serve()
        return
    print("opencv %s" % cv2.__version__)
    for path in a.files:
        try:
            npix = load(path).size
        except IOError as e:
            sys.stderr.write("%s\n" % e)
            sys.exit(1)
        reps = a.reps if a.reps > 0 else (5 if npix > 1_000_000 else 30)
        t1 = best_ns_per_px(path, reps, 1)
        tn = best_ns_per_px(path, reps, a.threads)
        print("RESULT %s %.3f %.3f %.6g" % (path, t1, tn, max_diff(path)))


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""Time OpenCV's exact Euclidean distance transform on the bitmaps written by
ct_bench_ddt (bench/bench_ddt.cpp), for the per-pixel ratio it prints.

Usage: bench_ddt_opencv.py [--threads N] [--reps R] FILE.pgm ...

A bitmap has 255 at feature pixels.  cv2.distanceTransform measures the
distance to the nearest ZERO pixel, so the input is inverted (features -> 0).
Mode: DIST_L2 with DIST_MASK_PRECISE (exact, Felzenszwalb-Huttenlocher).
For each file prints
    RESULT <file> <ns/pixel, 1 thread> <ns/pixel, N threads> <max |ours - cv|>
where the last field compares with FILE.dt.f32 (our unconstrained Euclidean
DT, float32, written by the bench) when present, else -1.
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


def best_time(fn, reps):
    best = float("inf")
    for _ in range(reps):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--reps", type=int, default=0, help="0: by size")
    ap.add_argument("files", nargs="+")
    a = ap.parse_args()
    print("opencv %s" % cv2.__version__)
    for path in a.files:
        img = cv2.imread(path, cv2.IMREAD_UNCHANGED)
        if img is None:
            sys.stderr.write("cannot read %s\n" % path)
            sys.exit(1)
        src = np.where(img > 0, 0, 1).astype(np.uint8)  # features -> 0
        npix = src.size
        reps = a.reps if a.reps > 0 else (5 if npix > 1_000_000 else 30)
        run = lambda: cv2.distanceTransform(src, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
        cv2.setNumThreads(1)
        t1 = best_time(run, reps)
        cv2.setNumThreads(a.threads)
        tn = best_time(run, reps)
        diff = -1.0
        ours = os.path.splitext(path)[0] + ".dt.f32"
        if os.path.exists(ours) and src.min() == 0:  # cv2 has no "no feature" value
            d = np.fromfile(ours, dtype=np.float32).reshape(src.shape)
            cv = run()
            diff = float(np.max(np.abs(d.astype(np.float64) - cv.astype(np.float64))))
        print("RESULT %s %.3f %.3f %.6g" % (path, t1 * 1e9 / npix, tn * 1e9 / npix, diff))


if __name__ == "__main__":
    main()

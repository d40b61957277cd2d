#!/usr/bin/python3
# viewshed_vs_gdal.py -- `make bench`: conetrace viewshed against GDAL's
# gdal_viewshed on the bundled DEM, the same observer (a post centre, 10 m
# above the ground) and targets on the ground, without curvature (-cc 0):
# agreement in % of posts, the posts each one alone sees, both times (whole
# processes, one thread for ours, in 7 alternating rounds: median and range,
# and the ratio's range over the rounds), and a picture
# of where they differ: BUILD/viewshed/viewshed_vs_gdal.png.  Then
# conetrace shadows (sun at 135, 20 deg) on packages of N = 8, 24, 64
# sectors: the cones (--method directional) against the exact ray cell by
# cell (--method incremental), one thread, 5 alternating rounds (median and
# range of the command's own timing), posts lit in one step (the post's own cone), steps,
# and the same shadow map from every N and both methods.
#
#   /usr/bin/python3 scripts/viewshed_vs_gdal.py [BUILD]
import os
import subprocess
import sys
import time

import numpy as np
from osgeo import gdal

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

gdal.UseExceptions()


def timed(cmd):
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - t0


def main():
    build = sys.argv[1] if len(sys.argv) > 1 else "build"
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    dem = os.path.join(root, "fixtures", "jacksboro_fault_dem.tif")
    out = os.path.join(build, "viewshed")
    os.makedirs(out, exist_ok=True)
    cli = os.path.join(build, "host_tools", "conetrace")
    pkg = os.path.join(out, "jacksboro.ctp")
    subprocess.run([cli, "build", dem, "--reduce", "3", "-o", pkg], check=True, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL)
    e, n, h = 201045.0, 4065855.0, 10.0  # a post centre near the middle of the tile
    ours = os.path.join(out, "ours.tif")
    theirs = os.path.join(out, "gdal.tif")
    cmd_ours = [cli, "viewshed", pkg, "--observer", "%.3f,%.3f,%.3f" % (e, n, h), "--threads", "1", "-o", ours]
    cmd_gdal = ["gdal_viewshed", "-q", "-ox", str(e), "-oy", str(n), "-oz", str(h), "-tz", "0", "-cc", "0",
                "-vv", "1", "-iv", "0", dem, theirs]
    timed(cmd_ours), timed(cmd_gdal)  # warm the page cache
    t_ours, t_gdal = [], []
    for k in range(7):  # alternating rounds: ab ba ab ...
        pair = (cmd_ours, cmd_gdal) if k % 2 == 0 else (cmd_gdal, cmd_ours)
        t = [timed(c) for c in pair]
        t_ours.append(t[0] if k % 2 == 0 else t[1])
        t_gdal.append(t[1] if k % 2 == 0 else t[0])
    ratios = sorted(a / b for a, b in zip(t_ours, t_gdal))
    a = gdal.Open(ours).ReadAsArray().astype(int)
    b = gdal.Open(theirs).ReadAsArray().astype(int)
    z = gdal.Open(dem).ReadAsArray().astype(float)
    m = a != 255
    agree = 100.0 * (a[m] == b[m]).mean()
    only_ours = int(((a == 1) & (b == 0)).sum())
    only_gdal = int(((a == 0) & (b == 1)).sum())
    print("viewshed vs gdal_viewshed (fixture, observer (%.0f, %.0f) %.0f m above the ground, targets on the ground, "
          "no curvature): agreement %.2f %% of %d posts; seen by both %d, only by conetrace %d, only by GDAL %d; "
          "time (whole processes, 7 alternating rounds, median [range]) conetrace %.3f s [%.3f-%.3f] (one thread), "
          "gdal_viewshed %.3f s [%.3f-%.3f]; conetrace / GDAL %.2f-%.2fx"
          % (e, n, h, agree, m.sum(), int(((a == 1) & (b == 1)).sum()), only_ours, only_gdal,
             sorted(t_ours)[3], min(t_ours), max(t_ours), sorted(t_gdal)[3], min(t_gdal), max(t_gdal),
             ratios[0], ratios[-1]))
    # the picture: hillshade, both seen, only one of them
    gy, gx = np.gradient(z, 30.0)
    shade = np.clip((-gx * (-0.5) - gy * 0.5 + 1) / np.sqrt(gx * gx + gy * gy + 1) / 1.3, 0, 1)
    rgb = np.dstack([0.25 + 0.7 * shade] * 3)
    both = (a == 1) & (b == 1)
    rgb[both] = 0.55 * rgb[both] + 0.45 * np.array([1.0, 0.84, 0.47])
    rgb[(a == 1) & (b == 0)] = [0.1, 0.65, 0.2]
    rgb[(a == 0) & (b == 1)] = [0.85, 0.1, 0.7]
    fig, ax = plt.subplots(figsize=(9, 8))
    ax.imshow(rgb, interpolation="nearest")
    g = gdal.Open(dem).GetGeoTransform()
    ax.plot([(e - g[0]) / g[1] - 0.5], [(n - g[3]) / g[5] - 0.5], "wo", mec="k", ms=8)
    from matplotlib.patches import Patch

    ax.legend(handles=[Patch(color=(1.0, 0.84, 0.47), label="seen by both"),
                       Patch(color=(0.1, 0.65, 0.2), label="seen only by conetrace (exact line of sight): %d" % only_ours),
                       Patch(color=(0.85, 0.1, 0.7), label="seen only by gdal_viewshed: %d" % only_gdal)],
              loc="lower right", fontsize=8)
    ax.set_title("Viewshed from 10 m above (%.0f, %.0f): agreement %.2f %%" % (e, n, agree))
    ax.set_xlabel("column (30 m posts)")
    ax.set_ylabel("row")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "viewshed_vs_gdal.png"), dpi=100)
    # shadows per N: the cones (directional) against the exact ray cell by
    # cell (incremental), alternating rounds, the same map from each
    first = None
    for nsec in (8, 24, 64):
        pk = os.path.join(out, "jacksboro_n%d.ctp" % nsec)
        subprocess.run([cli, "build", dem, "--sectors", str(nsec), "--reduce", "3", "-o", pk], check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        times = {"directional": [], "incremental": []}
        lines, maps = {}, {}
        for k in range(5):
            order = ("directional", "incremental") if k % 2 == 0 else ("incremental", "directional")
            for meth in order:
                sh = os.path.join(out, "shadow_n%d_%s.tif" % (nsec, meth))
                r = subprocess.run([cli, "shadows", pk, "--sun", "135,20", "--method", meth, "--threads", "1",
                                    "-o", sh], check=True, capture_output=True, text=True)
                times[meth].append(float(r.stderr.strip().split()[-2]))
                lines[meth] = r.stderr.strip()
                maps[meth] = gdal.Open(sh).ReadAsArray()
        same_methods = (maps["directional"] == maps["incremental"]).all()
        if first is None:
            first = maps["directional"]
        same_n = (maps["directional"] == first).all()
        td, ti = sorted(times["directional"]), sorted(times["incremental"])
        print("shadows N = %2d: %s; directional %.3f s [%.3f-%.3f], incremental %.3f s [%.3f-%.3f] (%s, %s)"
              % (nsec, lines["directional"].split(": ", 1)[1].rsplit(";", 1)[0], td[2], td[0], td[-1], ti[2], ti[0],
                 ti[-1], "the same map from both" if same_methods else "MAPS DIFFER",
                 "the same map as N = 8" if same_n else "A DIFFERENT MAP FROM N = 8"))


if __name__ == "__main__":
    main()

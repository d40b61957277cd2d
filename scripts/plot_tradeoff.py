#!/usr/bin/python3
# plot_tradeoff.py -- the plots of `make tradeoff` from DIR/tradeoff.csv
# (bench/tradeoff.cpp): DIR/tradeoff_time_error.png (time against error, the
# Pareto front marked; the chord sweep in its own panel, its error taken
# against the finest chord), DIR/tradeoff_time_size.png (time against
# package size) and DIR/tradeoff_steps_N.png (steps against N for each r).
# Prints the Pareto front as a Markdown table.  Debian's matplotlib:
# run with /usr/bin/python3.
import csv
import math
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def load(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def num(x):
    try:
        return float(x)
    except ValueError:
        return math.nan


def label(ax, xlabel, ylabel, title, legend=True):
    """Axis labels, title, a log-friendly grid and (when asked) the legend."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    if legend:
        ax.legend(fontsize=8)


def save(fig, path):
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main():
    d = sys.argv[1] if len(sys.argv) > 1 else "build/tradeoff"
    rows = load(d + "/tradeoff.csv")
    # one point per setting: mean time over the scenes every setting has
    # (the four on the plain DEM: the package knobs skip the tiled one),
    # worst RMS error
    common = set(r["scene"] for r in rows if r["knob"] == "package") or set(r["scene"] for r in rows)
    by = defaultdict(list)
    for r in rows:
        if r["scene"] in common:
            by[(r["knob"], r["value"])].append(r)
    pts = []
    for (knob, value), rs in by.items():
        ns = sum(num(r["ns_per_px"]) for r in rs) / len(rs)
        err = max(num(r["err_rms_m"]) for r in rs)
        p99 = max(num(r["err_p99_m"]) for r in rs)
        wrong = sum(int(r["wrong_surface"]) for r in rs)
        size = sum(num(r["package_x_dem"]) for r in rs) / len(rs)
        steps = sum(num(r["steps_per_px"]) for r in rs) / len(rs)
        pts.append(dict(knob=knob, value=value, ns=ns, err=err, p99=p99, wrong=wrong, size=size, steps=steps,
                        ref=rs[0]["err_ref"], scenes=len(rs)))
    colors = {"package": "tab:blue", "slices": "tab:cyan", "builder": "tab:purple", "method": "tab:green",
              "effects": "tab:red", "grid": "tab:orange", "chord": "tab:brown"}

    # --- time against error
    truth = [p for p in pts if p["ref"] == "truth" and not math.isnan(p["err"])]
    # (the finest chord itself, the reference, has no error to show)
    chord = [p for p in pts if p["knob"] == "chord" and not math.isnan(p["p99"]) and p["p99"] > 0]
    front = []
    for p in sorted(truth, key=lambda q: (q["ns"], q["err"])):
        if not front or p["err"] < front[-1]["err"]:
            front.append(p)
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(13, 5.2), gridspec_kw=dict(width_ratios=[2, 1]))
    for knob in colors:
        ps = [p for p in truth if p["knob"] == knob]
        if ps:
            ax.scatter([p["ns"] for p in ps], [max(p["err"], 1e-5) for p in ps], c=colors[knob], label=knob, s=28)
    ax.plot([p["ns"] for p in front], [max(p["err"], 1e-5) for p in front], "k--", lw=1, label="Pareto front")
    for p in front:
        ax.annotate(p["value"], (p["ns"], max(p["err"], 1e-5)), fontsize=7, xytext=(4, 3), textcoords="offset points")
    ax.set_xscale("log")
    ax.set_yscale("log")
    label(ax, "time per pixel, unprojection included (ns, mean over the 4 scenes on the plain DEM)",
          "horizontal error RMS vs ground truth (m, worst scene)",
          "What accuracy costs in time (one knob at a time from the defaults)")
    if chord:
        cs = sorted(chord, key=lambda q: q["ns"])
        bx.plot([p["ns"] for p in cs], [max(p["p99"], 1e-7) for p in cs], "o-", c=colors["chord"])
        for p in cs:
            bx.annotate(p["value"], (p["ns"], max(p["p99"], 1e-7)), fontsize=7, xytext=(4, 3), textcoords="offset points")
        bx.set_xscale("log")
        bx.set_yscale("log")
        label(bx, "time per pixel (ns)", "error p99 vs the finest chord (m)", "true Earth: the piece tolerance (chord)",
              legend=False)
    save(fig, d + "/tradeoff_time_error.png")

    # --- time against package size
    fig, ax = plt.subplots(figsize=(8, 5))
    pk = [p for p in pts if p["knob"] in ("package", "slices", "builder")]
    for knob in ("package", "slices", "builder"):
        ps = [p for p in pk if p["knob"] == knob]
        ax.scatter([p["size"] for p in ps], [p["ns"] for p in ps], c=colors[knob], label=knob, s=28)
        for p in ps:
            ax.annotate(p["value"], (p["size"], p["ns"]), fontsize=7, xytext=(3, 2), textcoords="offset points")
    ax.set_xscale("log")
    label(ax, "package size (x the 16-bit DEM)", "time per pixel (ns, mean over the scenes on the plain DEM)",
          "Time against package size")
    save(fig, d + "/tradeoff_time_size.png")

    # --- steps against N for each r
    fig, ax = plt.subplots(figsize=(8, 5))
    grid = defaultdict(dict)
    for p in pts:
        if p["knob"] != "package":
            continue
        n, r = p["value"].split()
        grid[int(r[1:])][int(n[1:])] = p["steps"]
    for r in sorted(grid):
        ns = sorted(grid[r])
        ax.plot(ns, [grid[r][n] for n in ns], "o-", label="r = %d" % r)
    ax.set_xscale("log", base=2)
    label(ax, "sectors N", "steps per pixel (directional, mean over the scenes)",
          "Steps against the number of sectors, per reduction r")
    save(fig, d + "/tradeoff_steps_N.png")

    print("| setting | time per pixel (ns) | error RMS / p99 (worst scene) | wrong surface | package (x DEM) |")
    print("|---|---|---|---|---|")
    for p in front:
        print("| %s %s | %.0f | %.2g / %.2g m | %d | %.2f |" % (p["knob"], p["value"], p["ns"], p["err"], p["p99"],
                                                              p["wrong"], p["size"]))


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""bench_targets.py -- issue 14's speed targets, read from one run of the benchmarks.

  scripts/bench_targets.py run BUILD      run BUILD/bench/ct_bench and ct_bench_geoloc (their output as
                                          they print it, and kept in BUILD/bench/logs/), then the summary
  scripts/bench_targets.py summary DIR    the summary of the logs kept in DIR (ct_bench.txt,
                                          ct_bench_geoloc.txt)

The summary compares each target with the ratios of that one run (this machine drifts by tens of percent
between runs, so only ratios within a run mean anything): directional against Embree and against the
max-mipmap (hierarchical) walk for every ray family, size and r (slice builder); paper-like rays at r = 1
against the incremental walk; the package at r = 3 against the DEM; and for geolocation on whole images
(ct_bench_geoloc) the trace with each scene's effects (and with the true Earth) against the straight trace,
directional against incremental on grazing3 and long30km, and a whole image's ns per pixel with the 8 px
unprojection grid; ratios the benchmark prints are taken as printed (rounded), the others are formed from
its times.
It reads the tables' own rows (`family rays | method steps median ns/ray ...`, `embree N ns/ray`,
`package N=.. r=..`, and ct_bench_geoloc's markdown table by its column names).  Exit status: 0 when the
benchmarks ran and their output could be read (met or not), 1 otherwise.
"""
import os
import re
import subprocess
import sys

BUILDER = "slice builder"  # the default builder; the targets are about its packages


def parse_bench(text):
    """ct_bench's output -> (rays, packages): rays[(dem, r, family)] = {method: ns, 'embree': ns};
    packages[(dem, r)] = size / DEM."""
    rays, packages = {}, {}
    dem = r = None
    family = None
    builder_ok = False
    for line in text.splitlines():
        m = re.match(r"=== (.*?): (\d+x\d+) posts", line)
        if m:
            dem, r, family, builder_ok = m.group(2), None, None, False
            continue
        m = re.match(r"package N=\d+ r=(\d+), (.*?): \d+ bytes = ([\d.]+)x the 16-bit DEM", line)
        if m:
            r, builder_ok = int(m.group(1)), m.group(2) == BUILDER
            if builder_ok:
                packages[(dem, r)] = float(m.group(3))
            continue
        if not builder_ok or dem is None or r is None:
            continue
        if "|" in line:
            left, right = line.split("|", 1)
            words = left.split()
            if len(words) == 2:
                family = words[0]
            elif len(words) != 1:
                continue
            parts = right.split()
            if family is None or len(parts) < 4:
                continue
            try:
                rays.setdefault((dem, r, family), {})[parts[0]] = float(parts[3])
            except ValueError:
                continue
            continue
        m = re.search(r"embree ([\d.]+) ns/ray", line)
        if m and family is not None:
            rays.setdefault((dem, r, family), {})["embree"] = float(m.group(1))
    return rays, packages


def number(cell, k=0):
    """The k-th number of a table cell ('328 / 5.9' -> 328 for k = 0, 5.9 for k = 1; '3.5x' -> 3.5); None
    for none."""
    nums = re.findall(r"-?\d+(?:\.\d+)?", cell.replace(",", ""))
    return float(nums[k]) if len(nums) > k else None


def parse_geoloc(text):
    """ct_bench_geoloc's table -> ({scene: {column name: cell}}, which pixels) (the first table with a
    'scene' column; which pixels: from its title, 'every pixel' or 'every 4th (--quick) pixel')."""
    header, rows, which = None, {}, "every pixel"
    for line in text.splitlines():
        m = re.match(r"geolocation benchmark: (every .*?pixel)", line)
        if m:
            which = m.group(1)
        if not line.startswith("|"):
            if header is not None and rows:
                break
            continue
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if header is None:
            if cells and cells[0] == "scene":
                header = cells
            continue
        if set(cells[0]) <= set("-: "):
            continue
        rows[cells[0]] = dict(zip(header, cells))
    return rows, which


def column(row, *names):
    for key, cell in row.items():
        if any(key.startswith(n) for n in names):
            return cell
    return None


class Report:
    def __init__(self):
        self.met = self.total = 0
        self.lines = []

    def check(self, label, value, ok, fmt="{:.2f}"):
        self.total += 1
        self.met += ok
        self.lines.append("    {:<34} {:>9}  {}".format(label, fmt.format(value), "met" if ok else "NOT MET"))

    def title(self, text):
        self.lines.append("  " + text)


def summary(rays, packages, geo, which="every pixel"):
    rep = Report()
    if rays:
        rep.title("directional / Embree time <= 1 (every family; the fixture, 403x344, at r = 1 and 3; 2048x2048 at 3):")
        for (dem, r, fam), m in sorted(rays.items()):
            if "embree" in m and "directional" in m:
                rep.check("{} r={} {}".format(dem, r, fam), m["directional"] / m["embree"],
                          m["directional"] <= m["embree"])
        rep.title("directional / hierarchical time < 1 (every family but nadir, every size and r):")
        for (dem, r, fam), m in sorted(rays.items()):
            if fam != "nadir" and "directional" in m and "hierarchical" in m:
                rep.check("{} r={} {}".format(dem, r, fam), m["directional"] / m["hierarchical"],
                          m["directional"] < m["hierarchical"], "{:.3f}")
        rep.title("paper-like rays at r = 1: incremental / directional time >= 15:")
        for (dem, r, fam), m in sorted(rays.items()):
            if fam == "paper_long" and r == 1 and "directional" in m and "incremental" in m:
                v = m["incremental"] / m["directional"]
                rep.check("{} r=1".format(dem), v, v >= 15, "{:.1f}x")
    if packages:
        rep.title("the package at r = 3 <= 3x the DEM:")
        for (dem, r), v in sorted(packages.items()):
            if r == 3:
                rep.check(dem, v, v <= 3, "{:.2f}x")
    if geo:
        rep.title("geolocation ({} of each image): trace with the scene's effects / straight <= 1.3:".format(which))
        for scene, row in geo.items():
            cell = column(row, "with effects / straight")
            v = number(cell) if cell else None
            bends = any(w in (row.get("effects") or "") for w in ("curvature", "refraction"))
            if v is not None and bends:
                rep.check(scene, v, v <= 1.3, "{:.2f}x")
        rep.title("the same with the true Earth (geoloc's default on UTM packages), its map fitted per batch:")
        for scene, row in geo.items():
            cell = column(row, "fitted / straight")
            v = number(cell) if cell else None
            if v is not None:
                rep.check(scene, v, v <= 1.3, "{:.2f}x")
        rep.title("directional >= 4x incremental with the scene's effects (grazing3, long30km):")
        for scene in ("grazing3", "long30km"):
            row = geo.get(scene)
            if row is None:
                continue
            # the benchmark's own ratio (its rounds' median); else from the two times
            v = number(column(row, "incr. / dir.") or "")
            if v is None:
                d = number(column(row, "directional:") or "")
                i = number(column(row, "incremental:") or "")
                v = i / d if d and i else None
            if v is not None:
                rep.check(scene, v, v >= 4, "{:.1f}x")
        rep.title("a whole image, 8 px grid: <= 300 ns per pixel on nadir, <= 600 on oblique30:")
        for scene, limit in (("nadir", 300), ("oblique30", 600)):
            row = geo.get(scene)
            cell = column(row, "whole image") if row else None
            v = number(cell, 1) if cell else None
            if v is not None:
                rep.check(scene, v, v <= limit, "{:.0f} ns")
    out = ["", "Issue 14's targets in this run ({} of {} met; ratios within this one run):".format(rep.met, rep.total)]
    return "\n".join(out + rep.lines), rep.total


def read(path):
    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            return f.read()
    except OSError as e:
        print("bench_targets: cannot read {}: {}".format(path, e.strerror), file=sys.stderr)
        return None


def run_logged(cmd, log):
    """cmd's output to stdout as it comes and into log (written whole, or not at all); its exit status."""
    part = log + ".part"
    try:
        with open(part, "w", encoding="utf-8") as f:
            p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, bufsize=1,
                                 encoding="utf-8", errors="replace")
            for line in p.stdout:
                sys.stdout.write(line)
                sys.stdout.flush()
                f.write(line)
            rc = p.wait()
        if rc == 0:
            os.replace(part, log)
        return rc
    finally:
        if os.path.exists(part):
            os.remove(part)


def main(argv):
    if len(argv) != 3 or argv[1] not in ("run", "summary"):
        print(__doc__.split("\n\n")[1], file=sys.stderr)
        return 1
    if argv[1] == "run":
        build = argv[2]
        logs = os.path.join(build, "bench", "logs")
        exes = [os.path.join(build, "bench", name) for name in ("ct_bench", "ct_bench_geoloc")]
        for exe in exes:
            if not os.access(exe, os.X_OK):
                print("bench_targets: {} missing (build the project first)".format(exe), file=sys.stderr)
                return 1
        os.makedirs(logs, exist_ok=True)
        for exe in exes:
            rc = run_logged([exe], os.path.join(logs, os.path.basename(exe) + ".txt"))
            if rc != 0:
                print("bench_targets: {} failed (exit status {})".format(exe, rc), file=sys.stderr)
                return 1
    else:
        logs = argv[2]
    bench, geoloc = read(os.path.join(logs, "ct_bench.txt")), read(os.path.join(logs, "ct_bench_geoloc.txt"))
    if bench is None or geoloc is None:
        return 1
    rays, packages = parse_bench(bench)
    geo, which = parse_geoloc(geoloc)
    text, n = summary(rays, packages, geo, which)
    if n == 0:
        print("bench_targets: no benchmark rows found in {}".format(logs), file=sys.stderr)
        return 1
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))

#!/usr/bin/python3
"""test_bench_targets.py -- scripts/bench_targets.py reads the benchmarks' tables and judges each target.

  test_bench_targets.py SCRIPT [CT_BENCH]

Synthetic logs in the benchmarks' printed formats, with times chosen so that every ratio and verdict is
known, must give exactly those ratios and verdicts (and the brute-force builder's rows must be ignored);
a log without rows must fail.  With CT_BENCH (build/bench/ct_bench), a small real run (--rays 40, the
fixture only, slice builder) must yield a verdict for every family at r = 1 and r = 3.
"""
import os
import re
import subprocess
import sys
import tempfile


def bench_rows(family, ns, steps=5.0):
    """ct_bench's rows for one family (bench.cpp's printf formats): ns = {method: ns per ray}."""
    out = []
    for k, m in enumerate(("incremental", "hierarchical", "cone", "directional")):
        out.append("%-11s %6d | %-13s %9.1f %7.0f %9.0f %9.2f %9.2f" %
                   (family if k == 0 else "", 100, m, steps, steps, ns[m], 1.0, 1.0))
    out.append("%-11s %6s   directional vs cone: %.2fx fewer steps" % ("", "", 1.0))
    if "embree" in ns:
        out.append("%-11s %6s   embree %.0f ns/ray (%ld hits vs our %ld): directional/embree time = %.2f" %
                   ("", "", ns["embree"], 10, 10, ns["directional"] / ns["embree"]))
    return out


def package_line(r, builder, ratio):
    return "\npackage N=24 r=%d, %s: %d bytes = %.2fx the 16-bit DEM (built in 0.1 s, 0.00%% degenerate cones)" % (
        r, builder, 1000, ratio)


GEO_HEADER = ("| scene | effects | pixels hit | unproject ns | directional: trace ns / steps | incremental: trace ns / "
              "steps | incr. / dir. time | straight dir.: trace ns / steps | error RMS / max (m), N points | with "
              "effects / straight (dir.) | true Earth dir.: trace ns / steps | true Earth / sphere | true Earth "
              "fitted dir.: trace ns / steps | fitted / straight | whole image dir. ns: lens / 8 px grid |")


def geo_row(scene, effects, d, i, straight_ratio, fitted_ratio, whole_grid):
    return "| %s | %s | 100.0 %% | 100 | %d / 3.0 | %d / 100.0 | %.1fx | 200 / 3.0 | 0.0005 / 0.0010, 2000 | %.2fx | %s | %s | %s | %s | 400 / %d |" % (
        scene, effects, d, i, i / d, straight_ratio, "-" if fitted_ratio is None else "3000 / 12.0",
        "-" if fitted_ratio is None else "10.00x", "-" if fitted_ratio is None else "1500 / 12.0",
        "-" if fitted_ratio is None else "%.2fx" % fitted_ratio, whole_grid)


def run(script, logdir):
    p = subprocess.run(["/usr/bin/python3", script, "summary", logdir], capture_output=True, text=True)
    return p.returncode, p.stdout + p.stderr


def verdicts(text):
    """{label: (value, met)} from the summary's lines, per section title."""
    out, section = {}, None
    for line in text.splitlines():
        if line.startswith("  ") and not line.startswith("    "):
            section = line.strip()
            continue
        m = re.match(r"    (.+?)\s+(-?[\d.]+)(x| ns)?\s+(met|NOT MET)$", line)
        if m:
            out[(section, m.group(1))] = (float(m.group(2)), m.group(4) == "met")
    return out


def find(v, prefix, label):
    """The verdict of label in the section whose title starts with prefix."""
    for (section, lab), got in v.items():
        if section.startswith(prefix) and lab == label:
            return got
    return None


def main():
    script = sys.argv[1]
    failures = []

    def expect(cond, what):
        if not cond:
            failures.append(what)

    with tempfile.TemporaryDirectory() as d:
        lines = ["", "=== jacksboro_fault_dem (fixture): 403x344 posts, 30 m grid, 0.0625 m per LSB ===",
                 "Embree 3 scene: 25.1 MB (90.5x the DEM), built in 0.47 s"]
        lines.append(package_line(1, "slice builder", 14.76))
        lines += bench_rows("grazing3", {"incremental": 1200, "hierarchical": 300, "cone": 400, "directional": 330,
                                         "embree": 110})
        lines += bench_rows("paper_long", {"incremental": 3000, "hierarchical": 450, "cone": 900, "directional": 200,
                                           "embree": 250})
        lines.append(package_line(3, "slice builder", 2.83))
        lines += bench_rows("horizontal", {"incremental": 900, "hierarchical": 270, "cone": 400, "directional": 250,
                                           "embree": 150})
        # the brute-force builder's rows (not the targets' packages): must be ignored
        lines.append(package_line(3, "brute-force builder", 3.5))
        lines += bench_rows("horizontal", {"incremental": 900, "hierarchical": 270, "cone": 400, "directional": 999,
                                           "embree": 1})
        with open(os.path.join(d, "ct_bench.txt"), "w") as f:
            f.write("\n".join(lines) + "\n")
        geo = ["geolocation benchmark: every pixel of each scene's image, one thread; ns per pixel", GEO_HEADER,
               "|---|" * 15,
               geo_row("nadir", "distortion", 200, 190, 1.00, None, 250),
               geo_row("oblique30", "distortion curvature", 300, 400, 1.25, 4.2, 650),
               geo_row("grazing3", "curvature refraction", 300, 1500, 1.35, 6.0, 380),
               geo_row("long30km", "distortion curvature refraction", 300, 1260, 1.29, 1.2, 400), ""]
        with open(os.path.join(d, "ct_bench_geoloc.txt"), "w") as f:
            f.write("\n".join(geo) + "\n")
        rc, text = run(script, d)
        expect(rc == 0, "summary of the synthetic logs exits 0 (got %d: %s)" % (rc, text))
        v = verdicts(text)
        want = {
            ("directional / Embree", "403x344 r=1 grazing3"): (3.0, False),
            ("directional / Embree", "403x344 r=1 paper_long"): (0.8, True),
            ("directional / Embree", "403x344 r=3 horizontal"): (250 / 150, False),
            ("directional / hierarc", "403x344 r=1 grazing3"): (1.1, False),
            ("directional / hierarc", "403x344 r=1 paper_long"): (200 / 450, True),
            ("directional / hierarc", "403x344 r=3 horizontal"): (250 / 270, True),
            ("paper-like rays at r ", "403x344 r=1"): (15.0, True),
            ("the package at r = 3", "403x344"): (2.83, True),
            ("geolocation (every pi", "oblique30"): (1.25, True),
            ("geolocation (every pi", "grazing3"): (1.35, False),
            ("geolocation (every pi", "long30km"): (1.29, True),
            ("the same with the tru", "oblique30"): (4.2, False),
            ("the same with the tru", "grazing3"): (6.0, False),
            ("the same with the tru", "long30km"): (1.2, True),
            ("directional >= 4x inc", "grazing3"): (5.0, True),
            ("directional >= 4x inc", "long30km"): (4.2, True),
            ("a whole image, 8 px g", "nadir"): (250, True),
            ("a whole image, 8 px g", "oblique30"): (650, False),
        }
        for key, (value, met) in want.items():
            got = find(v, *key)
            expect(got is not None, "no verdict for %s" % (key,))
            if got is not None:
                expect(abs(got[0] - value) <= 0.006 * max(1.0, abs(value)), "%s: %s, want %.3f" % (key, got[0], value))
                expect(got[1] == met, "%s: verdict %s, want %s" % (key, got[1], met))
        expect(not any(k[1] == "nadir" and k[0].startswith("geolocation") for k in v),
               "nadir (no bending) judged on effects / straight")
        expect(len(v) == len(want), "%d verdicts, want %d:\n%s" % (len(v), len(want), text))
        expect("(11 of 18 met;" in text, "the count of met targets:\n" + text)
        # a log without rows fails
        with open(os.path.join(d, "ct_bench.txt"), "w") as f:
            f.write("nothing here\n")
        with open(os.path.join(d, "ct_bench_geoloc.txt"), "w") as f:
            f.write("nothing here\n")
        rc, text = run(script, d)
        expect(rc != 0, "logs without rows must fail")
        # a missing log fails
        os.remove(os.path.join(d, "ct_bench.txt"))
        rc, text = run(script, d)
        expect(rc != 0 and "cannot read" in text, "a missing log must fail with its name")

        if len(sys.argv) > 2:
            # a small real run of ct_bench: every family has a verdict at r = 1 and r = 3
            p = subprocess.run([sys.argv[2], "--rays", "40", "--no-2048", "--only-slices"], capture_output=True,
                               text=True)
            expect(p.returncode == 0, "ct_bench --rays 40 exit status %d" % p.returncode)
            with open(os.path.join(d, "ct_bench.txt"), "w") as f:
                f.write(p.stdout)
            with open(os.path.join(d, "ct_bench_geoloc.txt"), "w") as f:
                f.write("\n".join(geo) + "\n")
            rc, text = run(script, d)
            v = verdicts(text)
            for r in (1, 3):
                for fam in ("oblique30", "grazing3", "horizontal", "paper_long"):
                    expect(find(v, "directional / hierarc", "403x344 r=%d %s" % (r, fam)) is not None,
                           "real run: no directional / hierarchical verdict for r=%d %s" % (r, fam))
                    if "embree" in p.stdout:
                        expect(find(v, "directional / Embree", "403x344 r=%d %s" % (r, fam)) is not None,
                               "real run: no Embree verdict for r=%d %s" % (r, fam))
            expect(find(v, "the package at r = 3", "403x344") is not None, "real run: no package verdict")

    for f in failures:
        print("FAIL:", f)
    print("test_bench_targets: %d failures" % len(failures))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())

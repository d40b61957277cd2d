#!/usr/bin/python3
"""Regenerate fixtures/jacksboro_fault_dem.tif from matplotlib's sample DEM.

Source: /usr/share/matplotlib/mpl-data/sample_data/jacksboro_fault_dem.npz
(Debian package python-matplotlib-data): array 'elevation', int16 metres,
public-domain USGS terrain at 3 arc-second posting.

The array is written unchanged (row 0 = first numpy row = top/north) as an
int16 GeoTIFF through ct_host::write_geotiff (tool ct_raw_to_geotiff), with a
NOMINAL georeference: a square 30 m grid in EPSG:32617 (WGS 84 / UTM 17N)
whose origin is rounded from the projected north-west corner of the DEM's
true extent.  The true posting (3", about 74 m E-W x 93 m N-S) is not kept.

Usage (Debian's numpy only works with /usr/bin/python3):
  cmake -S . -B build && cmake --build build --target ct_raw_to_geotiff
  /usr/bin/python3 scripts/make_fixture_jacksboro.py [--build-dir build]
      [--tool PATH/ct_raw_to_geotiff] [--npz FILE] [--out FILE]
Output is byte-for-byte reproducible for a given libtiff/zlib.
"""
import argparse
import os
import subprocess
import sys
import tempfile

try:
    import numpy as np
except ImportError:
    if os.path.realpath(sys.executable) != os.path.realpath("/usr/bin/python3") and \
            os.path.exists("/usr/bin/python3"):
        os.execv("/usr/bin/python3", ["/usr/bin/python3"] + sys.argv)
    raise

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
NPZ = "/usr/share/matplotlib/mpl-data/sample_data/jacksboro_fault_dem.npz"

# Nominal georeference (see fixtures/README.md).  The DEM's true NW corner,
# 36.7329 N 84.4138 W, projects to about (195147, 4070680) in UTM 17N.
EPSG = 32617
ORIGIN_E = 195000.0
ORIGIN_N = 4071000.0
POSTING = 30.0


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--npz", default=NPZ)
    ap.add_argument("--out", default=os.path.join(REPO, "fixtures", "jacksboro_fault_dem.tif"))
    ap.add_argument("--build-dir", default=os.path.join(REPO, "build"),
                    help="CMake build dir; ct_raw_to_geotiff is built there if --tool is not given")
    ap.add_argument("--tool", help="path to an already built ct_raw_to_geotiff")
    args = ap.parse_args()

    with np.load(args.npz) as d:
        z = np.array(d["elevation"])
    if z.dtype != np.int16 or z.ndim != 2:
        sys.exit("unexpected array: %s %s" % (z.dtype, z.shape))
    height, width = z.shape

    tool = args.tool
    if not tool:
        subprocess.run(["cmake", "--build", args.build_dir, "--target", "ct_raw_to_geotiff"],
                       check=True)
        tool = os.path.join(args.build_dir, "host_tools", "tools", "ct_raw_to_geotiff")

    with tempfile.TemporaryDirectory() as tmp:
        raw = os.path.join(tmp, "elevation.raw")
        np.ascontiguousarray(z, dtype="<i2").tofile(raw)
        subprocess.run([tool, "--in", raw, "--width", str(width), "--height", str(height),
                        "--type", "int16",
                        "--origin-e", repr(ORIGIN_E), "--origin-n", repr(ORIGIN_N),
                        "--posting", repr(POSTING), "--epsg", str(EPSG),
                        "--out", args.out], check=True)

    print("%s: %d x %d (width x height) int16, min %d, max %d, mean %.10g, sum %d" %
          (args.out, width, height, z.min(), z.max(), z.mean(), int(z.sum(dtype=np.int64))))
    print("corners: [0,0]=%d [0,-1]=%d [-1,0]=%d [-1,-1]=%d" %
          (z[0, 0], z[0, -1], z[-1, 0], z[-1, -1]))


if __name__ == "__main__":
    main()

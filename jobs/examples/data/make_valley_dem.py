#!/usr/bin/python3
"""Writes valley_dem.tif, the small georeferenced DEM of jobs/examples/gis_relief.json.

A synthetic terrain (no outside data): 128 x 128 texels of 2 m in EPSG:32633 (WGS 84 / UTM zone 33N), a valley
running north-south between two ridges, with terraces cut into its eastern slope, a few knolls and a 3 x 3
hole of NoData (-9999) that the job fills. Heights in metres, Float32, rounded to centimetres so that the
DEFLATE-compressed GeoTIFF stays a few KB. Deterministic: the same bytes every run.

    jobs/examples/data/make_valley_dem.py        # needs gdal_translate (Debian: gdal-bin)
"""
import math
import os
import subprocess
import tempfile

SIZE = 128
PIXEL = 2.0                      # metres
ORIGIN = (500000.0, 5100000.0)   # upper-left corner, UTM 33N
NODATA = -9999.0


def height(i, j):
    x, y = i * PIXEL, j * PIXEL                     # metres east and south of the corner
    centre = 128.0 + 18.0 * math.sin(y / 55.0)       # the valley floor's line wanders
    across = (x - centre) / 70.0
    h = 420.0 + 55.0 * (1.0 - math.exp(-across * across)) - 0.08 * y
    if x > centre + 20.0:                            # terraces on the eastern slope, 3 m steps
        h = h - 0.6 * (h - 3.0 * math.floor(h / 3.0))
    for kx, ky, r, a in ((60, 40, 14, 9), (200, 180, 18, 12), (90, 210, 10, 6)):
        d2 = ((x - kx) ** 2 + (y - ky) ** 2) / (r * r)
        h += a * math.exp(-d2)                       # knolls
    h += 0.8 * math.sin(x / 7.0 + 0.3) * math.sin(y / 9.0)  # small ripples
    return round(h, 2)


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    with tempfile.TemporaryDirectory() as tmp:
        asc = os.path.join(tmp, "valley.asc")
        with open(asc, "w") as f:
            f.write(f"ncols {SIZE}\nnrows {SIZE}\nxllcorner {ORIGIN[0]}\n"
                    f"yllcorner {ORIGIN[1] - SIZE * PIXEL}\ncellsize {PIXEL}\nNODATA_value {NODATA:.0f}\n")
            for j in range(SIZE):
                row = []
                for i in range(SIZE):
                    hole = 70 <= i < 73 and 30 <= j < 33
                    row.append(f"{NODATA:.0f}" if hole else f"{height(i, j):.2f}")
                f.write(" ".join(row) + "\n")
        out = os.path.join(here, "valley_dem.tif")
        subprocess.run(["gdal_translate", "-q", "-ot", "Float32", "-a_srs", "EPSG:32633",
                        "-a_nodata", f"{NODATA:.0f}", "-co", "COMPRESS=DEFLATE", "-co", "PREDICTOR=3",
                        "-co", "TILED=NO", "-mo", "SOURCE=hfbake jobs/examples/data/make_valley_dem.py",
                        asc, out], check=True)
        aux = out + ".aux.xml"
        if os.path.exists(aux):
            os.remove(aux)
    print(out)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Sky-view factor and openness of a DEM: GDAL in, hfbake.relief, GeoTIFFs out with the DEM's CRS and
geotransform.

    gdal_relief.py DEM.tif OUT_DIR [--directions K] [--radius R]

Writes OUT_DIR/svf.tif, openness_positive.tif and openness_negative.tif (float32, one band). hfbake.read_dem
reads the DEM with the checks a job naming the file gets (a projected CRS, square pixels, heights in the
pixels' unit, NoData and NaN texels as holes filled for the bake) and says what a job would warn about (a
CRS far from true scale); the holes are written back as NoData.
"""
import argparse
import pathlib
import sys

import numpy as np
from osgeo import gdal

import hfbake

gdal.UseExceptions()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dem")
    parser.add_argument("out_dir", type=pathlib.Path)
    parser.add_argument("--directions", type=int, default=16)
    parser.add_argument("--radius", type=float, default=None, help="search radius in world units")
    args = parser.parse_args()

    try:
        dem = hfbake.read_dem(args.dem)
    except hfbake.InputError as e:
        raise SystemExit(f"gdal_relief: {e}")
    for warning in dem.warnings:
        print(f"gdal_relief: warning: {warning}", file=sys.stderr)
    layers = hfbake.relief(dem.heights, directions=args.directions, search_radius=args.radius,
                           layers=["svf", "openness_positive", "openness_negative"], **dem.keys)

    args.out_dir.mkdir(parents=True, exist_ok=True)
    driver = gdal.GetDriverByName("GTiff")
    for name, values in layers.items():
        rows, columns = values.shape
        out = driver.Create(str(args.out_dir / f"{name}.tif"), columns, rows, 1, gdal.GDT_Float32,
                            options=["COMPRESS=DEFLATE"])
        out.SetGeoTransform(dem.geotransform)
        out.SetProjection(dem.projection)
        out_band = out.GetRasterBand(1)
        out_band.SetNoDataValue(-9999.0)
        out_band.WriteArray(np.where(dem.holes, np.float32(-9999.0), values))
        out = None  # closes the file


if __name__ == "__main__":
    main()

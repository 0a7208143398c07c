#!/usr/bin/env python3
"""Sky-view factor and openness of a DEM: GDAL in, hfbake.relief, GeoTIFFs out with the DEM's CRS and
geotransform.

    gdal_relief.py DEM.tif OUT_DIR [--directions K] [--radius R]

Writes OUT_DIR/svf.tif, openness_positive.tif and openness_negative.tif (float32, one band). The DEM must
be in a projected CRS with square pixels (gdalwarp -t_srs / -tr first if not; or bake a job naming the file,
which reads a geographic DEM's texel sizes itself: docs/gis.md). Heights are taken in the pixels' unit; a band
that declares another (GDAL's unit type: metres on a CRS in feet) is converted into it, and the factor is
printed. Its NoData texels (the band's NoData value, NaN included) are filled from their neighbours for the
bake and written back as NoData.
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

    dem = gdal.Open(args.dem)
    band = dem.GetRasterBand(1)
    heights = band.ReadAsArray().astype(np.float32)
    geotransform = dem.GetGeoTransform()
    if geotransform[2] != 0 or geotransform[4] != 0 or abs(geotransform[1]) != abs(geotransform[5]):
        raise SystemExit(f"{args.dem}: needs square, unrotated pixels (gdalwarp -tr S S first)")
    crs = dem.GetSpatialRef()
    if crs is not None and crs.IsGeographic():
        raise SystemExit(f"{args.dem}: its pixels are degrees of a geographic CRS: gdalwarp -t_srs to a projected "
                         "CRS first, or bake a job naming the file (docs/gis.md, Geographic DEMs)")
    nodata = band.GetNoDataValue()
    holes = ~np.isfinite(heights)
    if nodata is not None:
        holes |= heights == nodata
    projected = crs is not None and crs.IsProjected()
    factor = hfbake.height_unit_factor(band.GetUnitType(), crs.GetLinearUnits() if projected else 1.0)
    if factor is not None and abs(factor - 1) > 1e-4:  # heights into the pixels' unit
        heights[~holes] *= np.float32(factor)
        print(f"gdal_relief: {args.dem}: the band's heights are in {band.GetUnitType()}, its pixels in "
              f"{crs.GetLinearUnitsName() if projected else 'metre'}: heights x {factor:.6g}", file=sys.stderr)

    layers = hfbake.relief(
        heights,
        texel_size=abs(geotransform[1]),
        directions=args.directions,
        search_radius=args.radius,
        layers=["svf", "openness_positive", "openness_negative"],
        nodata="fill" if nodata is not None else None,
        nodata_value=nodata,
    )

    args.out_dir.mkdir(parents=True, exist_ok=True)
    driver = gdal.GetDriverByName("GTiff")
    for name, values in layers.items():
        out = driver.Create(str(args.out_dir / f"{name}.tif"), dem.RasterXSize, dem.RasterYSize, 1,
                            gdal.GDT_Float32, options=["COMPRESS=DEFLATE"])
        out.SetGeoTransform(geotransform)
        out.SetProjection(dem.GetProjection())
        out_band = out.GetRasterBand(1)
        out_band.SetNoDataValue(-9999.0)
        out_band.WriteArray(np.where(holes, np.float32(-9999.0), values))
        out = None  # closes the file


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Sky-view factor and openness of a DEM: GDAL in, hfbake.relief, GeoTIFFs out with the DEM's CRS and
geotransform.

    gdal_relief.py DEM.tif OUT_DIR [--directions K] [--radius R]

Writes OUT_DIR/svf.tif, openness_positive.tif and openness_negative.tif (float32, one band). The DEM must
be in a projected CRS with square pixels in the heights' unit (gdalwarp -t_srs / -tr first if not; or bake
a job naming the file, which reads a geographic DEM's texel sizes itself: docs/gis.md); its NoData texels
(the band's NoData value, NaN included) are filled from their neighbours for the bake and written back as
NoData.
"""
import argparse
import pathlib

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
    holes = ~np.isfinite(heights)
    if nodata is not None:
        holes |= heights == nodata
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

"""The examples run as a user runs them, their outputs checked against the command's."""

import json
import pathlib
import subprocess
import sys

import numpy as np
import pytest

from conftest import SOURCE_DIR, read_exr, run_cli, terrain

gdal = pytest.importorskip("osgeo.gdal")


def write_geotiff(path, heights, nodata=None):
    gdal.UseExceptions()
    ds = gdal.GetDriverByName("GTiff").Create(str(path), heights.shape[1], heights.shape[0], 1, gdal.GDT_Float32)
    ds.SetGeoTransform((500000.0, 2.0, 0.0, 5200000.0, 0.0, -2.0))
    srs = gdal.osr.SpatialReference()
    srs.ImportFromEPSG(32633)
    ds.SetProjection(srs.ExportToWkt())
    band = ds.GetRasterBand(1)
    if nodata is not None:
        band.SetNoDataValue(nodata)
    band.WriteArray(heights)
    ds = None


def test_gdal_relief_example(tmp_path):
    heights = terrain(48, 40, seed=11) * 10
    heights[7, 9] = -32768.0  # a hole
    dem = tmp_path / "dem.tif"
    write_geotiff(dem, heights, nodata=-32768.0)
    script = SOURCE_DIR / "python" / "examples" / "gdal_relief.py"
    subprocess.run([sys.executable, str(script), str(dem), str(tmp_path / "py"), "--directions", "16",
                    "--radius", "30"], check=True)

    job = {"version": 1, "name": "t", "height": {"image": "dem.tif", "nodata": "fill"},
           "bake": [{"method": "relief", "directions": 16, "search_radius": 30.0,
                     "layers": ["svf", "openness_positive", "openness_negative"]}],
           "output": {"pixel_type": "float"}}
    (tmp_path / "job.json").write_text(json.dumps(job))
    run_cli("bake", tmp_path / "job.json", "--out", tmp_path / "cli", "--quiet", "--no-cache")
    exr = read_exr(tmp_path / "cli" / "t.relief.exr")

    for name in ("svf", "openness_positive", "openness_negative"):
        ds = gdal.Open(str(tmp_path / "py" / f"{name}.tif"))
        assert ds.GetGeoTransform() == (500000.0, 2.0, 0.0, 5200000.0, 0.0, -2.0)
        assert gdal.osr.SpatialReference(wkt=ds.GetProjection()).GetAuthorityCode(None) == "32633"
        values = ds.GetRasterBand(1).ReadAsArray()
        assert values[7, 9] == -9999.0
        values[7, 9] = exr[f"{name}.Y"][7, 9]
        assert np.array_equal(values.view(np.uint32), exr[f"{name}.Y"].view(np.uint32)), name

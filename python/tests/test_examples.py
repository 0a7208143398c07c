"""The examples run as a user runs them, their outputs checked against the command's."""

import json
import pathlib
import subprocess
import sys

import numpy as np
import pytest

from conftest import SOURCE_DIR, OpenImageIO, read_exr, run_cli, terrain

gdal = pytest.importorskip("osgeo.gdal")


def write_geotiff(path, heights, nodata=None, epsg=32633, geotransform=(500000.0, 2.0, 0.0, 5200000.0, 0.0, -2.0),
                  scale=None, offset=None):
    """heights as a one-band GeoTIFF: Int16 or UInt16 for those arrays, else Float32; with the band's declared
    scale and offset when given."""
    gdal.UseExceptions()
    kind = {np.dtype(np.int16): gdal.GDT_Int16, np.dtype(np.uint16): gdal.GDT_UInt16}.get(heights.dtype,
                                                                                         gdal.GDT_Float32)
    ds = gdal.GetDriverByName("GTiff").Create(str(path), heights.shape[1], heights.shape[0], 1, kind)
    ds.SetGeoTransform(geotransform)
    srs = gdal.osr.SpatialReference()
    srs.ImportFromEPSG(epsg)
    ds.SetProjection(srs.ExportToWkt())
    band = ds.GetRasterBand(1)
    if nodata is not None:
        band.SetNoDataValue(nodata)
    if scale is not None:
        band.SetScale(scale)
    if offset is not None:
        band.SetOffset(offset)
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


def test_gdal_relief_example_nan_holes_and_geographic_dems(tmp_path):
    # A NaN NoData value: its holes are written back as NoData (NaN never equals itself).
    heights = terrain(48, 40, seed=11) * 10
    heights[7, 9] = np.nan
    dem = tmp_path / "dem.tif"
    write_geotiff(dem, heights, nodata=float("nan"))
    script = SOURCE_DIR / "python" / "examples" / "gdal_relief.py"
    subprocess.run([sys.executable, str(script), str(dem), str(tmp_path / "py"), "--radius", "30"], check=True)
    ds = gdal.Open(str(tmp_path / "py" / "svf.tif"))  # held: a band outlives no dataset
    values = ds.GetRasterBand(1).ReadAsArray()
    assert values[7, 9] == -9999.0
    assert np.count_nonzero(values == -9999.0) == 1
    # Degrees are not metres: a lon/lat DEM is refused, naming it.
    geo = tmp_path / "lonlat.tif"
    write_geotiff(geo, terrain(48, 40, seed=11) * 10, epsg=4326, geotransform=(15.0, 1e-5, 0.0, 46.0, 0.0, -1e-5))
    result = subprocess.run([sys.executable, str(script), str(geo), str(tmp_path / "geo")], capture_output=True,
                            text=True)
    assert result.returncode != 0
    assert "lonlat.tif" in result.stderr and "geographic" in result.stderr
    assert not (tmp_path / "geo").exists()


def test_gdal_relief_example_converts_heights_into_the_pixels_unit(tmp_path):
    # Heights in metres (the band says so) on 2 US-survey-foot pixels (EPSG:2263) bake as the same heights
    # given in feet: x 3937 / 1200, the factor printed.
    heights = terrain(48, 40, seed=11) * 10
    gt = (300000.0, 2.0, 0.0, 200000.0, 0.0, -2.0)
    metres = tmp_path / "metres.tif"
    write_geotiff(metres, heights, epsg=2263, geotransform=gt)
    ds = gdal.Open(str(metres), gdal.GA_Update)
    ds.GetRasterBand(1).SetUnitType("m")
    ds = None
    feet = tmp_path / "feet.tif"
    write_geotiff(feet, (heights * np.float32(3937 / 1200)).astype(np.float32), epsg=2263, geotransform=gt)
    script = SOURCE_DIR / "python" / "examples" / "gdal_relief.py"
    converted = subprocess.run([sys.executable, str(script), str(metres), str(tmp_path / "m"), "--radius", "30"],
                               capture_output=True, text=True, check=True)
    assert "heights are in m, its pixels in US survey foot: heights x 3.28083" in converted.stderr
    plain = subprocess.run([sys.executable, str(script), str(feet), str(tmp_path / "f"), "--radius", "30"],
                           capture_output=True, text=True, check=True)
    assert "heights x" not in plain.stderr
    for name in ("svf", "openness_positive", "openness_negative"):
        a, b = gdal.Open(str(tmp_path / "m" / f"{name}.tif")), gdal.Open(str(tmp_path / "f" / f"{name}.tif"))
        assert np.array_equal(a.GetRasterBand(1).ReadAsArray(), b.GetRasterBand(1).ReadAsArray()), name


def read_png(path):
    inp = OpenImageIO.ImageInput.open(str(path))
    spec = inp.spec()
    pixels = inp.read_image("uint16").reshape(spec.height, spec.width, spec.nchannels)
    inp.close()
    return pixels


SCALE = 24.0 / 65535.0  # the 16-bit levels back to the 24 texels of relief they span


def test_texture_from_image_example(tmp_path):
    levels = np.round((terrain(32, 32, seed=17) + 12.0) / 24.0 * 65535.0).clip(0, 65535).astype(np.uint16)
    image = tmp_path / "height.png"
    out = OpenImageIO.ImageOutput.create(str(image))
    out.open(str(image), OpenImageIO.ImageSpec(32, 32, 1, "uint16"))
    out.write_image(levels.reshape(32, 32, 1))
    out.close()
    script = SOURCE_DIR / "python" / "examples" / "texture_from_image.py"
    subprocess.run([sys.executable, str(script), str(image), str(tmp_path / "rock"), "--height-scale", repr(SCALE),
                    "--directions", "16"], check=True)

    job = {"version": 1, "name": "t", "height": {"image": "height.png", "height_scale": SCALE, "wrap": "repeat"},
           "bake": [{"method": "p1", "directions": 16, "layers": ["ao", "bent_normal"]}],
           "output": {"pixel_type": "float"}}
    (tmp_path / "job.json").write_text(json.dumps(job))
    run_cli("bake", tmp_path / "job.json", "--out", tmp_path / "cli", "--quiet", "--no-cache")
    exr = read_exr(tmp_path / "cli" / "t.p1.exr")

    def quantized(v):
        return np.round(np.clip(v, 0.0, 1.0) * 65535.0).astype(np.uint16)

    assert np.array_equal(read_png(tmp_path / "rock_ao.png")[:, :, 0], quantized(exr["ao.Y"]))
    normal = read_png(tmp_path / "rock_bent_normal.png")
    for c, axis in enumerate("XYZ"):
        assert np.array_equal(normal[:, :, c], quantized(0.5 + 0.5 * exr[f"bent_normal.{axis}"])), axis

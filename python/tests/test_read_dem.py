"""hfbake.read_dem: a DEM read for the array functions with the checks and warnings a job naming the file
gets (the command's own reading is the truth)."""

import json
import subprocess
import sys

import numpy as np
import pytest

import hfbake
from conftest import SOURCE_DIR, run_cli, terrain
from test_examples import write_geotiff

gdal = pytest.importorskip("osgeo.gdal")


def test_a_web_mercator_dem_warns_as_the_command_does(tmp_path):
    # 46.5 degrees north: Web Mercator's metres are 1/cos(46.5) = 1.45 ground metres.
    dem = tmp_path / "mercator.tif"
    x, y = 1669792.0, 5861197.0  # EPSG:3857 near 15 E, 46.5 N
    write_geotiff(dem, terrain(40, 32, seed=13) * 10, epsg=3857, geotransform=(x, 2.0, 0.0, y, 0.0, -2.0))
    d = hfbake.read_dem(dem)
    assert len(d.warnings) == 1 and "times too flat" in d.warnings[0], d.warnings
    job = {"version": 1, "name": "m", "height": {"image": str(dem)}, "bake": [{"method": "relief"}]}
    (tmp_path / "m.json").write_text(json.dumps(job))
    said = run_cli("validate", tmp_path / "m.json", check=False)
    command = next(line for line in said.stderr.splitlines() if "too flat" in line)
    assert d.warnings[0].split(": ", 1)[1] in command  # the same sentence
    # The example passes the warning on.
    result = subprocess.run([sys.executable, SOURCE_DIR / "python" / "examples" / "gdal_relief.py", dem,
                             tmp_path / "out"], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert "times too flat" in result.stderr


def test_nan_holes_without_a_declared_nodata_are_filled_and_kept_as_holes(tmp_path):
    heights = terrain(40, 32, seed=13) * 10
    heights[5, 6] = np.nan
    dem = tmp_path / "dem.tif"
    write_geotiff(dem, heights)  # no NoData value: the NaN is a hole all the same
    d = hfbake.read_dem(dem)
    assert d.keys["nodata"] == "fill" and d.holes[5, 6] and np.count_nonzero(d.holes) == 1
    svf = hfbake.relief(d.heights, directions=8, layers=["svf"], **d.keys)["svf"]
    assert np.isfinite(svf).all()
    result = subprocess.run([sys.executable, SOURCE_DIR / "python" / "examples" / "gdal_relief.py", dem,
                             tmp_path / "out"], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    out = gdal.Open(str(tmp_path / "out" / "svf.tif")).ReadAsArray()
    assert out[5, 6] == -9999.0 and np.count_nonzero(out == -9999.0) == 1


def test_pixel_sides_equal_to_1e9_are_square_and_others_are_refused_naming_both(tmp_path):
    dem = tmp_path / "noisy.tif"
    write_geotiff(dem, terrain(40, 32, seed=13), geotransform=(500000.0, 2.000000000001, 0.0, 5200000.0, 0.0,
                                                                 -1.999999999999))
    assert hfbake.read_dem(dem).keys["texel_size"] == pytest.approx(2.0, rel=1e-9)
    wide = tmp_path / "wide.tif"
    write_geotiff(wide, terrain(40, 32, seed=13), geotransform=(500000.0, 2.0, 0.0, 5200000.0, 0.0, -1.5))
    with pytest.raises(hfbake.InputError) as e:
        hfbake.read_dem(wide)
    assert e.value.file == str(wide) and "2.0 x 1.5" in str(e.value)


def test_a_float64_sentinel_beyond_float_range_is_a_hole_only_as_the_nodata_value(tmp_path):
    heights = (terrain(40, 32, seed=13) * 10).astype(np.float64)
    heights[3, 4] = -1e300
    dem = tmp_path / "f64.tif"
    ds = gdal.GetDriverByName("GTiff").Create(str(dem), 40, 32, 1, gdal.GDT_Float64)
    ds.SetGeoTransform((500000.0, 2.0, 0.0, 5200000.0, 0.0, -2.0))
    srs = gdal.osr.SpatialReference()
    srs.ImportFromEPSG(32633)
    ds.SetProjection(srs.ExportToWkt())
    ds.GetRasterBand(1).SetNoDataValue(-1e300)
    ds.GetRasterBand(1).WriteArray(heights)
    ds = None
    d = hfbake.read_dem(dem)
    assert d.holes[3, 4] and np.count_nonzero(d.holes) == 1 and d.keys["nodata"] == "fill"
    # Without that NoData value the sentinel is no hole: refused naming the texel, as the command does
    # (docs/gis.md).
    ds = gdal.Open(str(dem), gdal.GA_Update)
    ds.GetRasterBand(1).DeleteNoDataValue()
    ds = None
    with pytest.raises(hfbake.InputError) as e:
        hfbake.read_dem(dem)
    assert e.value.file == str(dem) and "texel (4, 3) is -1e+300, beyond a float's range" in str(e.value)


def test_missing_files_geographic_and_crs_less_rasters_are_refused_naming_the_file(tmp_path):
    with pytest.raises(hfbake.InputError, match="no such file"):
        hfbake.read_dem(tmp_path / "none.tif")
    geo = tmp_path / "lonlat.tif"
    write_geotiff(geo, terrain(40, 32, seed=13), epsg=4326, geotransform=(15.0, 1e-5, 0.0, 46.0, 0.0, -1e-5))
    with pytest.raises(hfbake.InputError, match="geographic"):
        hfbake.read_dem(geo)
    with pytest.raises(hfbake.InputError, match="no band 2"):
        hfbake.read_dem(tmp_path / "lonlat.tif", band=2)



def test_a_raster_without_a_geotransform_is_refused_as_a_job_refuses_it(tmp_path):
    # A CRS but no geotransform, and ground control points in place of one: no texel size or place.
    heights = terrain(40, 32, seed=13) * 10
    srs = gdal.osr.SpatialReference()
    srs.ImportFromEPSG(32633)
    crs_only = tmp_path / "crs_only.tif"
    ds = gdal.GetDriverByName("GTiff").Create(str(crs_only), 40, 32, 1, gdal.GDT_Float32)
    ds.SetProjection(srs.ExportToWkt())
    ds.GetRasterBand(1).WriteArray(heights)
    ds = None
    gcps = tmp_path / "gcps.tif"
    ds = gdal.GetDriverByName("GTiff").Create(str(gcps), 40, 32, 1, gdal.GDT_Float32)
    ds.SetGCPs([gdal.GCP(500000.0, 5200000.0, 0, 0, 0), gdal.GCP(500080.0, 5200000.0, 0, 40, 0),
                gdal.GCP(500000.0, 5199936.0, 0, 0, 32)], srs.ExportToWkt())
    ds.GetRasterBand(1).WriteArray(heights)
    ds = None
    for dem, said in ((crs_only, "but no geotransform"), (gcps, "is placed by ground control points")):
        with pytest.raises(hfbake.InputError) as e:
            hfbake.read_dem(dem)
        assert said in str(e.value), str(e.value)
        job = {"version": 1, "name": "g", "height": {"image": str(dem)}, "bake": [{"method": "relief"}]}
        (tmp_path / "g.json").write_text(json.dumps(job))
        command = run_cli("validate", tmp_path / "g.json", check=False)
        assert command.returncode == 2 and said in command.stderr, command.stderr


def test_a_south_up_or_mirrored_raster_is_read_north_up(tmp_path):
    # The same ground stored north-up, south-up and east-west: one north-up array and geotransform.
    heights = terrain(40, 32, seed=13) * 10
    north_up = tmp_path / "n.tif"
    write_geotiff(north_up, heights)
    south_up = tmp_path / "s.tif"
    write_geotiff(south_up, heights[::-1, :], geotransform=(500000.0, 2.0, 0.0, 5200000.0 - 64.0, 0.0, 2.0))
    mirrored = tmp_path / "m.tif"
    write_geotiff(mirrored, heights[:, ::-1], geotransform=(500080.0, -2.0, 0.0, 5200000.0, 0.0, -2.0))
    truth = hfbake.read_dem(north_up)
    for dem in (south_up, mirrored):
        d = hfbake.read_dem(dem)
        assert np.array_equal(d.heights, truth.heights), dem
        assert d.geotransform == pytest.approx(truth.geotransform), dem


def test_a_declared_scale_and_offset_are_warned_as_the_command_warns(tmp_path):
    dem = tmp_path / "scaled.tif"
    ds = gdal.GetDriverByName("GTiff").Create(str(dem), 40, 32, 1, gdal.GDT_UInt16)
    ds.SetGeoTransform((500000.0, 2.0, 0.0, 5200000.0, 0.0, -2.0))
    srs = gdal.osr.SpatialReference()
    srs.ImportFromEPSG(32633)
    ds.SetProjection(srs.ExportToWkt())
    band = ds.GetRasterBand(1)
    band.WriteArray((terrain(40, 32, seed=13) * 100 + 3000).astype(np.uint16))
    band.SetScale(0.01)
    band.SetOffset(250.0)
    ds = None
    d = hfbake.read_dem(dem)
    said = [w for w in d.warnings if "scale 0.01 and offset 250, not applied" in w]
    assert len(said) == 1, d.warnings
    job = {"version": 1, "name": "s", "height": {"image": str(dem)}, "bake": [{"method": "relief"}]}
    (tmp_path / "s.json").write_text(json.dumps(job))
    assert "scale 0.01 and offset 250, not applied" in run_cli("validate", tmp_path / "s.json",
                                                                check=False).stderr
    # unscale=True: the stored values as the band declares them, NoData still a hole.
    ds = gdal.Open(str(dem))  # held: a band outlives no dataset
    stored = ds.GetRasterBand(1).ReadAsArray().astype(np.float64)
    ds = None
    u = hfbake.read_dem(dem, unscale=True)
    assert np.array_equal(u.heights, (stored * 0.01 + 250).astype(np.float32))
    assert [w for w in u.warnings if "stored x 0.01 + 250 (unscale=True)" in w], u.warnings
    assert not [w for w in u.warnings if "not applied" in w], u.warnings
    with pytest.raises(hfbake.InputError, match="must be True or False"):
        hfbake.read_dem(dem, unscale="yes")


def test_a_pngs_nodata_is_a_height_as_a_job_reads_it(tmp_path):
    # A placed 16-bit PNG whose tRNS colour (0) GDAL reports as NoData: the job bakes it as heights (one of
    # them 0), and read_dem reads the same heights, with no holes.
    stored = np.round(terrain(40, 32, seed=13) * 100 + 3000).astype(np.uint16)
    stored[10:14, 10:14] = 0
    write_geotiff(tmp_path / "dem.tif", stored, nodata=0)
    png = tmp_path / "dem.png"
    gdal.GetDriverByName("PNG").CreateCopy(str(png), gdal.Open(str(tmp_path / "dem.tif")), options=["WORLDFILE=YES"])
    ds = gdal.Open(str(png))  # held: a band outlives no dataset
    assert ds.GetRasterBand(1).GetNoDataValue() == 0
    ds = None
    d = hfbake.read_dem(png)
    assert not d.holes.any()
    assert np.array_equal(d.heights, stored.astype(np.float32))
    job = {"version": 1, "name": "p", "height": {"image": str(png)}, "bake": [{"method": "relief"}]}
    (tmp_path / "p.json").write_text(json.dumps(job))
    said = run_cli("validate", tmp_path / "p.json", check=False)
    assert said.returncode == 0, said.stderr
    assert "heights 0 .. " in said.stderr, said.stderr


def test_a_mask_band_marks_holes_as_a_job_reads_them(tmp_path):
    dem = tmp_path / "masked.tif"
    write_geotiff(dem, terrain(40, 32, seed=13) * 10)
    gdal.SetConfigOption("GDAL_TIFF_INTERNAL_MASK", "NO")
    try:
        ds = gdal.Open(str(dem), gdal.GA_Update)
        ds.CreateMaskBand(gdal.GMF_PER_DATASET)
        valid = np.full((32, 40), 255, np.uint8)
        valid[:, 30:] = 0
        ds.GetRasterBand(1).GetMaskBand().WriteArray(valid)
        ds = None
    finally:
        gdal.SetConfigOption("GDAL_TIFF_INTERNAL_MASK", None)
    d = hfbake.read_dem(dem)
    assert np.count_nonzero(d.holes) == 320 and d.holes[:, 30:].all() and d.keys["nodata"] == "fill"
    job = {"version": 1, "name": "k", "height": {"image": str(dem), "nodata": "fill"}, "bake": [{"method": "relief"}]}
    (tmp_path / "k.json").write_text(json.dumps(job))
    assert "320 texels without a height" in run_cli("validate", tmp_path / "k.json", check=False).stderr


def test_a_mosaics_gap_is_refused_as_a_job_refuses_it(tmp_path):
    # Two sources with a source's width between them: GDAL reads 0 m in the gap unless it is NoData.
    heights = terrain(24, 20, seed=3) * 10 + 300
    write_geotiff(tmp_path / "west.tif", heights, geotransform=(500000.0, 1.0, 0.0, 5100020.0, 0.0, -1.0))
    write_geotiff(tmp_path / "east.tif", heights, geotransform=(500048.0, 1.0, 0.0, 5100020.0, 0.0, -1.0))
    gdal.BuildVRT(str(tmp_path / "gap.vrt"), [str(tmp_path / "west.tif"), str(tmp_path / "east.tif")])
    with pytest.raises(hfbake.InputError) as caught:
        hfbake.read_dem(tmp_path / "gap.vrt")
    assert "33.3 % of it is covered by none of its data" in str(caught.value)
    job = {"version": 1, "name": "g", "height": {"image": str(tmp_path / "gap.vrt")}, "bake": [{"method": "relief"}]}
    (tmp_path / "g.json").write_text(json.dumps(job))
    said = run_cli("validate", tmp_path / "g.json", check=False)
    assert said.returncode == 2
    assert caught.value.message in said.stderr  # the same sentence
    gdal.BuildVRT(str(tmp_path / "holes.vrt"), [str(tmp_path / "west.tif"), str(tmp_path / "east.tif")],
                  VRTNodata=-9999)
    d = hfbake.read_dem(tmp_path / "holes.vrt")
    assert d.holes[:, 24:48].all() and not d.holes[:, :24].any()


def test_heights_without_a_unit_on_a_crs_in_feet_are_noted_as_the_command_notes(tmp_path):
    # EPSG:2263 (New York Long Island, US survey feet); the band declares no unit for its heights.
    dem = tmp_path / "feet.tif"
    write_geotiff(dem, terrain(24, 20, seed=5) * 10 + 100, epsg=2263,
                  geotransform=(980000.0, 6.0, 0.0, 200000.0, 0.0, -6.0))
    d = hfbake.read_dem(dem)
    notes = [w for w in d.warnings if "declares no unit" in w]
    assert len(notes) == 1, d.warnings
    assert "heights taken in US survey foot; heights in metres need height_scale 3.28083" in notes[0]
    job = {"version": 1, "name": "f", "height": {"image": str(dem)}, "bake": [{"method": "relief"}]}
    (tmp_path / "f.json").write_text(json.dumps(job))
    said = run_cli("validate", tmp_path / "f.json", check=False)
    assert notes[0].split(": ", 1)[1] in said.stderr  # the same sentence
    # A band that says its heights are in feet gets no note.
    ds = gdal.Open(str(dem), gdal.GA_Update)
    ds.GetRasterBand(1).SetUnitType("US survey foot")
    ds = None
    assert not [w for w in hfbake.read_dem(dem).warnings if "declares no unit" in w]


def test_a_float32_bands_nodata_is_compared_as_the_float_it_stores(tmp_path):
    # A Float32 band holds the float nearest a NoData value declared in decimal (-9999.9 in a VRT, as
    # gdalbuildvrt -vrtnodata writes it): those texels are the holes, as a job reading the file finds them.
    heights = (terrain(40, 32, seed=13) * 10).astype(np.float32)
    heights[10:12, 20:22] = np.float32(-9999.9)
    src = tmp_path / "src.tif"
    write_geotiff(src, heights)
    vrt = tmp_path / "dem.vrt"
    gdal.Translate(str(vrt), str(src), format="VRT")
    ds = gdal.Open(str(vrt), gdal.GA_Update)
    ds.GetRasterBand(1).SetNoDataValue(-9999.9)
    ds = None
    d = hfbake.read_dem(vrt)
    assert np.count_nonzero(d.holes) == 4 and d.holes[10:12, 20:22].all() and d.keys["nodata"] == "fill"
    job = {"version": 1, "name": "v", "height": {"image": str(vrt), "nodata": "fill"},
           "bake": [{"method": "relief"}]}
    (tmp_path / "v.json").write_text(json.dumps(job))
    said = run_cli("validate", tmp_path / "v.json", check=False)
    assert "4 texels without a height" in said.stderr, said.stderr

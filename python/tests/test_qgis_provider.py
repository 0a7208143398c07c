"""The QGIS Processing provider (python/qgis_provider) run headless through qgis_process: its GeoTIFFs hold
the command's values, with the input's CRS and geotransform."""

import json
import os
import pathlib
import shutil
import subprocess

import numpy as np
import pytest

from conftest import SOURCE_DIR, read_exr, run_cli, terrain
from test_examples import write_geotiff

gdal = pytest.importorskip("osgeo.gdal")

# Debian's /usr/bin/qgis_process wraps qgis_process.bin with QGIS_OPTS from /etc/default/qgis, an option
# (--noversioncheck) that qgis_process 3.22 refuses: the binary itself when it is there.
QGIS_PROCESS = next((p for p in ("/usr/bin/qgis_process.bin", shutil.which("qgis_process")) if p and
                     os.path.exists(p)), None)
pytestmark = pytest.mark.skipif(QGIS_PROCESS is None, reason="qgis_process is not installed (Debian qgis)")

# (algorithm, parameters, method, entry keys, layer)
ALGORITHMS = [
    ("svf", {"DIRECTIONS": 16, "RADIUS": 30}, "relief", {"directions": 16, "search_radius": 30.0}, "svf"),
    ("openness_negative", {"DIRECTIONS": 16, "RADIUS": 30}, "relief", {"directions": 16, "search_radius": 30.0},
     "openness_negative"),
    ("horizons", {"DIRECTIONS": 8, "RADIUS": 0}, "relief", {"directions": 8}, "horizon_deg"),
    ("ao", {"DIRECTIONS": 16}, "p1", {"directions": 16}, "ao"),
    ("hbao", {"DIRECTIONS": 8, "RADIUS": 6}, "hbao", {"directions": 8, "radius": 6.0}, "obscurance"),
]


@pytest.fixture(scope="module")
def qgis_env(tmp_path_factory):
    home = tmp_path_factory.mktemp("qgis-home")
    env = dict(os.environ, QT_QPA_PLATFORM="offscreen", HOME=str(home), XDG_RUNTIME_DIR=str(home),
               QGIS_PLUGINPATH=str(SOURCE_DIR / "python" / "qgis_provider"))
    result = subprocess.run([QGIS_PROCESS, "plugins", "enable", "hfbake_provider"], env=env,
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stdout + result.stderr
    return env


@pytest.mark.parametrize("algorithm,params,method,entry,layer", ALGORITHMS, ids=[a[0] for a in ALGORITHMS])
def test_algorithm_writes_the_commands_values(tmp_path, qgis_env, algorithm, params, method, entry, layer):
    dem = tmp_path / "dem.tif"
    write_geotiff(dem, terrain(40, 32, seed=13) * 10)
    out = tmp_path / f"{algorithm}.tif"
    args = [f"{k}={v}" for k, v in {"INPUT": dem, "BAND": 1, **params, "OUTPUT": out}.items()]
    result = subprocess.run([QGIS_PROCESS, "run", f"hfbake:{algorithm}", "--", *args], env=qgis_env,
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stdout + result.stderr

    job = {"version": 1, "name": "t", "height": {"image": "dem.tif"},
           "bake": [{"method": method, **entry, "layers": [layer]}], "output": {"pixel_type": "float"}}
    (tmp_path / "job.json").write_text(json.dumps(job))
    run_cli("bake", tmp_path / "job.json", "--out", tmp_path / "cli", "--quiet", "--no-cache")
    exr = read_exr(tmp_path / "cli" / f"t.{method}.exr")
    expected = [exr[f"{layer}.Y"]] if f"{layer}.Y" in exr else [
        exr[f"{layer}.{k:03d}"] for k in range(entry["directions"])]

    ds = gdal.Open(str(out))
    assert ds.GetGeoTransform() == (500000.0, 2.0, 0.0, 5200000.0, 0.0, -2.0)
    assert gdal.osr.SpatialReference(wkt=ds.GetProjection()).GetAuthorityCode(None) == "32633"
    assert ds.RasterCount == len(expected)
    for k, plane in enumerate(expected):
        values = ds.GetRasterBand(k + 1).ReadAsArray()
        assert np.array_equal(values.view(np.uint32), plane.view(np.uint32)), f"{algorithm} band {k + 1}"


def test_nan_holes_are_nodata_and_geographic_layers_are_refused(tmp_path, qgis_env):
    heights = terrain(40, 32, seed=13) * 10
    heights[5, 6] = np.nan
    dem = tmp_path / "dem.tif"
    write_geotiff(dem, heights, nodata=float("nan"))
    out = tmp_path / "svf.tif"
    result = subprocess.run([QGIS_PROCESS, "run", "hfbake:svf", "--", f"INPUT={dem}", "BAND=1", "DIRECTIONS=8",
                             "RADIUS=10", f"OUTPUT={out}"], env=qgis_env, capture_output=True, text=True)
    assert result.returncode == 0, result.stdout + result.stderr
    ds = gdal.Open(str(out))  # held: a band outlives no dataset
    values = ds.GetRasterBand(1).ReadAsArray()
    assert values[5, 6] == -9999.0
    assert np.count_nonzero(values == -9999.0) == 1

    geo = tmp_path / "lonlat.tif"
    write_geotiff(geo, terrain(40, 32, seed=13) * 10, epsg=4326, geotransform=(15.0, 1e-5, 0.0, 46.0, 0.0, -1e-5))
    result = subprocess.run([QGIS_PROCESS, "run", "hfbake:svf", "--", f"INPUT={geo}", "BAND=1",
                             f"OUTPUT={tmp_path / 'geo.tif'}"], env=qgis_env, capture_output=True, text=True)
    assert result.returncode != 0
    assert "geographic" in result.stdout + result.stderr


def svf_through_qgis(tmp_path, qgis_env, dem):
    """hfbake:svf (8 directions, radius 10) of `dem`: what qgis_process printed, and the GeoTIFF's values."""
    out = tmp_path / f"svf_{dem.stem}.tif"
    result = subprocess.run([QGIS_PROCESS, "run", "hfbake:svf", "--", f"INPUT={dem}", "BAND=1", "DIRECTIONS=8",
                             "RADIUS=10", f"OUTPUT={out}"], env=qgis_env, capture_output=True, text=True)
    assert result.returncode == 0, result.stdout + result.stderr
    ds = gdal.Open(str(out))  # held: a band outlives no dataset
    return result.stdout + result.stderr, ds.GetRasterBand(1).ReadAsArray()


def test_heights_in_another_unit_than_the_pixels_are_converted(tmp_path, qgis_env):
    # Metres (the band says so) on US-survey-foot pixels bake as the same heights given in feet.
    heights = terrain(40, 32, seed=13) * 10
    gt = (300000.0, 2.0, 0.0, 200000.0, 0.0, -2.0)
    metres, feet = tmp_path / "metres.tif", tmp_path / "feet.tif"
    write_geotiff(metres, heights, epsg=2263, geotransform=gt)
    ds = gdal.Open(str(metres), gdal.GA_Update)
    ds.GetRasterBand(1).SetUnitType("m")
    ds = None
    write_geotiff(feet, (heights * np.float32(3937 / 1200)).astype(np.float32), epsg=2263, geotransform=gt)
    said, a = svf_through_qgis(tmp_path, qgis_env, metres)
    said_feet, b = svf_through_qgis(tmp_path, qgis_env, feet)
    assert "heights x 3.28083" in said and "heights x 3.28083" not in said_feet, said
    assert np.array_equal(a, b)


def test_bad_layers_and_outputs_fail_with_a_message_not_a_traceback(tmp_path, qgis_env):
    heights = terrain(40, 32, seed=13) * 10
    dem = tmp_path / "dem.tif"
    write_geotiff(dem, heights)
    square_degrees = tmp_path / "degrees.tif"  # pixels square in degrees: still geographic
    write_geotiff(square_degrees, heights, epsg=4326, geotransform=(10.0, 1e-4, 0.0, 47.0, 0.0, -1e-4))
    no_crs = tmp_path / "plain.tif"
    ds = gdal.GetDriverByName("GTiff").Create(str(no_crs), 40, 32, 1, gdal.GDT_Float32)
    ds.GetRasterBand(1).WriteArray(heights)
    ds = None
    cases = [
        ({"INPUT": dem, "BAND": 2}, "has no band 2 (bands are numbered from 1; it has 1)"),
        ({"INPUT": dem, "OUTPUT": tmp_path / "no" / "svf.tif"}, "its folder does not exist"),
        ({"INPUT": dem, "OUTPUT": tmp_path / "a_folder"}, "is a folder"),
        ({"INPUT": dem, "OUTPUT": dem}, "which the input layer reads"),
        ({"INPUT": square_degrees}, "geographic"),
        ({"INPUT": no_crs}, "has no CRS"),
    ]
    (tmp_path / "a_folder").mkdir()
    genuine = dem.read_bytes()
    for params, expect in cases:
        args = {"BAND": 1, "DIRECTIONS": 8, "OUTPUT": tmp_path / "out.tif", **params}
        result = subprocess.run([QGIS_PROCESS, "run", "hfbake:svf", "--"] + [f"{k}={v}" for k, v in args.items()],
                                env=qgis_env, capture_output=True, text=True)
        text = result.stdout + result.stderr
        assert result.returncode != 0, text
        assert expect in text, text
        assert "Traceback" not in text and "AttributeError" not in text, text
    assert dem.read_bytes() == genuine


def test_direction_bands_name_their_bearing_and_a_mercator_dem_warns(tmp_path, qgis_env):
    # K = 16 on a north-up raster: direction 12 (azimuth 270, towards -rows) looks north. A north-down raster
    # is read north up (read_dem turns it, and its geotransform), so its output's direction 12 looks north too.
    for name, geotransform, north_band in [("up", (500000.0, 2.0, 0.0, 5200000.0, 0.0, -2.0), 13),
                                           ("down", (500000.0, 2.0, 0.0, 5100000.0, 0.0, 2.0), 13)]:
        dem = tmp_path / f"{name}.tif"
        write_geotiff(dem, terrain(40, 32, seed=13) * 10, geotransform=geotransform)
        out = tmp_path / f"h_{name}.tif"
        result = subprocess.run([QGIS_PROCESS, "run", "hfbake:horizons", "--", f"INPUT={dem}", "BAND=1",
                                 "DIRECTIONS=16", "RADIUS=0", f"OUTPUT={out}"], env=qgis_env, capture_output=True,
                                text=True)
        assert result.returncode == 0, result.stdout + result.stderr
        ds = gdal.Open(str(out))
        assert ds.GetRasterBand(north_band).GetDescription().endswith("bearing 0.00 degrees (clockwise from grid "
                                                                      "north)"), name
        assert "bearing 90.00" in ds.GetRasterBand(1).GetDescription()  # +columns: east either way
        assert ds.GetGeoTransform()[5] < 0, name  # written north up

    mercator = tmp_path / "mercator.tif"
    write_geotiff(mercator, terrain(40, 32, seed=13) * 10, epsg=3857,
                  geotransform=(1669792.0, 2.0, 0.0, 5861197.0, 0.0, -2.0))
    result = subprocess.run([QGIS_PROCESS, "run", "hfbake:svf", "--", f"INPUT={mercator}", "BAND=1",
                             "DIRECTIONS=8", "RADIUS=10", f"OUTPUT={tmp_path / 'm.tif'}"], env=qgis_env,
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "times too flat" in result.stdout + result.stderr


def test_a_declared_scale_and_offset_apply_as_qgis_shows_the_band(tmp_path, qgis_env):
    # An Int16 band of centimetres above 250 m (scale 0.01, offset 250), which QGIS shows as metres, bakes the
    # same values as the float DEM of those metres.
    centimetres = np.round(terrain(40, 32, seed=13) * 1000).astype(np.int16)
    metres = (centimetres.astype(np.float64) * 0.01 + 250).astype(np.float32)
    scaled, plain = tmp_path / "scaled.tif", tmp_path / "plain.tif"
    write_geotiff(plain, metres)
    write_geotiff(scaled, centimetres, scale=0.01, offset=250.0)
    said, a = svf_through_qgis(tmp_path, qgis_env, scaled)
    said_plain, b = svf_through_qgis(tmp_path, qgis_env, plain)
    assert "stored x 0.01 + 250" in said and "stored x" not in said_plain, said
    assert np.array_equal(a, b)


def test_the_bakes_warnings_reach_the_log(tmp_path, qgis_env):
    # Heights 50 times the field's side: the relief warning hfbake's array functions give, in the log.
    dem = tmp_path / "steep.tif"
    write_geotiff(dem, terrain(40, 32, seed=13) * 4000)
    result = subprocess.run([QGIS_PROCESS, "run", "hfbake:svf", "--", f"INPUT={dem}", "BAND=1", "DIRECTIONS=8",
                             "RADIUS=10", f"OUTPUT={tmp_path / 's.tif'}"], env=qgis_env, capture_output=True,
                            text=True)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "steeper than any terrain" in result.stdout, result.stdout

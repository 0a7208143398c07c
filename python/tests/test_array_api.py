"""The array API against `hfbake bake`: the same field and parameters give the same bits."""

import warnings

import numpy as np
import pytest

import hfbake
from conftest import assert_same_bits, cli_bake, run_cli, terrain, write_job

# (method, parameters, field keys): small fields and direction counts; a per-direction layer, colour and
# vector layers and a repeat field among them.
CASES = [
    ("p1", {"directions": 16, "layers": ["ao", "vsky", "horizon", "bent_normal"]}, {}),
    ("p1", {"directions": 8, "layers": ["ao", "horizon_distance"]}, {"wrap": "repeat", "texel_size": 0.5}),
    ("p2", {"directions": 8, "bounces": 1}, {}),
    ("nlp", {"directions": 8, "layers": ["direct", "total"]}, {}),
    ("hbao", {"directions": 8, "falloff": "none", "layers": ["obscurance", "ao", "bent_normal"]}, {}),
    ("lsao", {"directions": 8, "radius": 6.0}, {"wrap": "repeat"}),
    ("farfield", {"directions": 8, "radius": 10.0}, {}),
    ("hsao", {"directions": 8, "radius": 6.0}, {}),
    ("vo", {"radius": 4.0}, {"height_scale": 2.0}),
    ("relief", {"directions": 16, "search_radius": 10.0,
                "layers": ["svf", "openness_positive", "openness_negative", "horizon_deg"]}, {"texel_size": 2.0}),
    ("sun", {"start": "2026-06-21T08:00", "end": "2026-06-21T16:00", "utc_offset": 0, "step_minutes": 60,
             "latitude": 46.0, "longitude": 15.0, "layers": ["irradiation", "sun_hours", "beam"]}, {}),
]


@pytest.mark.parametrize("method,params,field", CASES, ids=[f"{c[0]}-{i}" for i, c in enumerate(CASES)])
def test_same_bits_as_the_command(tmp_path, method, params, field):
    heights = terrain(40, 32, seed=len(method))
    mine = getattr(hfbake, method)(heights, **field, **params)
    theirs = cli_bake(tmp_path, heights, {"method": method, **params}, height_keys=field)
    assert_same_bits(mine, theirs)


def test_every_method_is_covered():
    assert {c[0] for c in CASES} == set(hfbake.methods)


def test_per_direction_layers_are_k_h_w():
    heights = terrain(24, 20)
    out = hfbake.p1(heights, directions=12, layers=["horizon", "ao"])
    assert out["horizon"].shape == (12, 20, 24)
    assert out["ao"].shape == (20, 24)


def test_same_bits_for_any_thread_count():
    heights = terrain(48, 40, seed=7)
    one = hfbake.p1(heights, directions=16, threads=1)
    two = hfbake.p1(heights, directions=16, threads=2)
    for name in one:
        assert np.array_equal(one[name].view(np.uint32), two[name].view(np.uint32))


def test_other_dtypes_and_layouts_are_the_float32_field():
    heights = terrain(30, 26, seed=3)
    ref = hfbake.hbao(heights, directions=8)
    for variant in (heights.astype(np.float64), np.asfortranarray(heights), heights.T.copy().T):
        out = hfbake.hbao(variant, directions=8)
        assert np.array_equal(out["obscurance"], ref["obscurance"])
    assert heights.flags.c_contiguous  # the caller's array is untouched


def test_progress_is_reported_on_the_calling_thread():
    import threading

    seen = []
    caller = threading.get_ident()
    # About 16 M texel-directions on one thread: many times the 50 ms between the caller's polls even on a
    # machine several times faster than p1's rate in docs/performance.md.
    hfbake.p1(terrain(512, 512), directions=64, threads=1,
              progress=lambda f: seen.append((f, threading.get_ident())))
    assert seen, "progress was never called"
    assert all(0.0 <= f <= 1.0 and t == caller for f, t in seen)
    assert seen[-1][0] == 1.0
    assert any(f < 1.0 for f, _ in seen), "no progress while baking"
    assert [f for f, _ in seen] == sorted(f for f, _ in seen)


def test_the_stubs_name_every_method():
    import ast
    import pathlib

    stub = pathlib.Path(hfbake.__file__).with_name("__init__.pyi")
    names = {node.name for node in ast.parse(stub.read_text()).body if isinstance(node, ast.FunctionDef)}
    assert set(hfbake.methods) | {"validate", "bake"} <= names


def test_help_lists_the_method_keys():
    assert "directions" in hfbake.p1.__doc__ and "search_radius" in hfbake.relief.__doc__
    with pytest.raises(hfbake.InputError):
        hfbake.hbao(terrain(8, 8), threads=-2)


def test_job_keys_a_method_key_shadows(tmp_path):
    heights = terrain(32, 24, seed=9)
    sun = [{"directional": {"direction": [0.3, 0.2, 0.9], "irradiance": 2.0}}]
    params = {"directions": 16, "lights": True, "layers": ["direct"]}
    mine = hfbake.p1(heights, job={"lights": sun}, **params)
    theirs = cli_bake(tmp_path, heights, {"method": "p1", **params}, job_keys={"lights": sun})
    assert_same_bits(mine, theirs)
    assert not np.array_equal(mine["direct"], hfbake.p1(heights, **params)["direct"])


def test_numpy_values_are_the_job_values():
    heights = terrain(24, 24, seed=2)
    plain = hfbake.relief(heights, directions=8, search_radius=5.0, layers=["svf", "horizon_deg"])
    numpy = hfbake.relief(heights, directions=np.int64(8), search_radius=np.float32(5.0),
                          layers=np.array(["svf", "horizon_deg"]))
    for name in plain:
        assert np.array_equal(plain[name], numpy[name])


def test_height_unit_factor_converts_a_bands_unit_into_the_pixels():
    us_foot = 1200 / 3937  # metres in a US survey foot (EPSG:9003)
    assert hfbake.height_unit_factor("m", us_foot) == pytest.approx(3.280833333, rel=1e-9)
    assert hfbake.height_unit_factor("Metre") == 1.0
    assert hfbake.height_unit_factor("ft") == pytest.approx(0.3048, rel=1e-12)
    assert hfbake.height_unit_factor("US survey foot", us_foot) == pytest.approx(1.0, rel=1e-12)
    assert hfbake.height_unit_factor("ft", us_foot) == pytest.approx(0.999998, rel=1e-6)
    assert hfbake.height_unit_factor("", 0.3048) is None
    assert hfbake.height_unit_factor(None) is None
    assert hfbake.height_unit_factor("furlong") is None


def test_a_sun_a_hair_off_an_axis_lights_flat_ground():
    # The sun at 269.997 degrees (the equator at 14:30 on the March equinox): its own search runs a hair off
    # the field's x axis, where a search that read past the field's last column shaded texels at random.
    flat = np.zeros((8, 8), np.float32)
    for _ in range(5):
        out = hfbake.sun(flat, start="2026-03-20T14:30", end="2026-03-20T14:31", utc_offset=0, step_minutes=1,
                         latitude=0, longitude=0, layers=["sun_hours", "beam"], threads=1)
        assert np.all(out["sun_hours"] == np.float32(1 / 60)), out["sun_hours"]
        assert np.ptp(out["beam"]) == 0 and out["beam"].min() > 12


@pytest.mark.parametrize("levels", ["uint16", "flat", "terrain"])
def test_the_array_functions_warn_about_the_heights_as_the_command_does(tmp_path, levels):
    import warnings

    from conftest import run_cli, write_job

    if levels == "uint16":  # 16-bit levels taken as world units: a relief far beyond 4 x the 64-unit side
        heights = (np.random.default_rng(0).random((64, 64)) * 65535).astype(np.uint16)
    elif levels == "flat":
        heights = np.full((64, 64), 3.0, np.float32)
    else:
        heights = terrain(64, 64)
    relief, side = float(heights.max()) - float(heights.min()), 64.0
    expected = relief == 0 or relief < 0.01 * side or relief > 4 * side  # docs/heights.md's rule
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        hfbake.p1(heights, directions=4)
    said = [str(w.message) for w in caught if w.category is UserWarning]
    assert len(said) == int(expected), said
    # The command's validate of the same heights (a float image: the array is converted to float) says the
    # same after its job file's name.
    job = write_job(tmp_path, heights.astype(np.float32), {"method": "p1", "directions": 4})
    lines = [line for line in run_cli("validate", job).stderr.splitlines() if line.startswith("hfbake: warning:")]
    assert [line.replace(f"hfbake: warning: {job}: ", "heights: ") for line in lines] == said
    if levels == "uint16":
        assert "steeper than any terrain" in said[0]
    if levels == "flat":
        assert said == ["heights: the field is flat (every height is 3): every method bakes it unoccluded"]


def test_a_few_outlying_texels_are_warned_in_an_image_not_in_an_array(tmp_path):
    # A plain with one tower: as an image a job names (a height map, no CRS) the range the tower sets is
    # warned; as an array (a DEM read by read_dem carries no CRS) it is baked without that warning.
    heights = np.zeros((64, 64), np.float32)
    heights[10, 20] = 20.0
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        hfbake.p1(heights, directions=4)
    assert not [w for w in caught if "stands out" in str(w.message)]
    job = write_job(tmp_path, heights, {"method": "p1", "directions": 4})
    said = run_cli("validate", job).stderr
    assert "but 1 texel stands out of them by up to 20 (the farthest at texel (20, 10))" in said, said


def test_earth_curvature_lowers_a_wall_by_d2_over_2r():
    # A wall 10 m high three km east of the receivers (30 texels of 100 m): with curvature and no refraction
    # its top is d^2 / (2 R) lower, R = 6371008.8 m (a sphere without a CRS, docs/gis.md).
    heights = np.zeros((16, 64), np.float32)
    heights[:, 40] = 10.0
    d, radius = 3000.0, 6371008.8
    flat = hfbake.relief(heights, texel_size=100.0, directions=4, search_radius=6000.0, layers=["horizon_deg"])
    curved = hfbake.relief(heights, texel_size=100.0, directions=4, search_radius=6000.0, layers=["horizon_deg"],
                           curvature=True, refraction=0.0)
    assert flat["horizon_deg"][0, 8, 10] == pytest.approx(np.degrees(np.arctan(10.0 / d)), abs=1e-4)
    assert curved["horizon_deg"][0, 8, 10] == pytest.approx(
        np.degrees(np.arctan((10.0 - d * d / (2 * radius)) / d)), abs=1e-4)
    with pytest.raises(hfbake.InputError) as caught:  # the job's rule: refraction only with curvature
        hfbake.relief(heights, refraction=0.1)
    assert caught.value.pointer == "/refraction"


def test_p1_ao_is_a_share_on_extreme_fields():
    # Spikes of 9e11 on a flat field and relief 1e11 times the texel: every direction's sky a sliver, whose
    # rounding could leave the mean a few 1e-8 below 0.
    rng = np.random.default_rng(2)
    rng.random((32, 32))
    for heights, texel in ((np.where(rng.random((32, 32)) > 0.9, 9e11, 0).astype(np.float32), 1.0),
                           ((rng.random((32, 32)) * 5e5).astype(np.float32), 1e-6)):
        ao = hfbake.p1(heights, texel_size=texel, directions=8, layers=["ao"], threads=1)["ao"]
        assert ao.min() >= 0 and ao.max() <= 1

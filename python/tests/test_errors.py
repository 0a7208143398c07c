"""Bad input raises hfbake.InputError (a ValueError) with the message `hfbake validate` prints for the same
job, its pointer relative to the keyword arguments; a cancelled bake raises and returns nothing."""

import threading

import warnings

import numpy as np
import pytest

import hfbake
from conftest import cli_errors, terrain, write_job


def cli_problem(tmp_path, heights, entry, height_keys=None):
    """(pointer, message) of the first line `hfbake validate` prints for the job."""
    lines = cli_errors(write_job(tmp_path, heights, entry, height_keys))
    assert lines
    file, pointer, message = lines[0].split(": ", 2)
    assert file.endswith("job.json")
    return pointer, message


@pytest.mark.parametrize(
    "entry",
    [
        {"method": "p1", "directions": "many"},  # a wrong type
        {"method": "p1", "directions": 0},  # out of the schema's range
        {"method": "p1", "directions": 2.5},  # not an integer
        {"method": "p1", "layers": ["ao", "sky"]},  # an unknown layer
        {"method": "p1", "layers": []},  # no layer
        {"method": "hbao", "radius": -1.0},
        {"method": "relief", "directions": 4, "search_radius": 1e9},  # a rule only the reader knows
        {"method": "p1", "direktions": 16},  # an unknown key
    ],
    ids=["type", "range", "integer", "layer", "no-layer", "hbao-radius", "relief-radius", "unknown-key"],
)
def test_bad_parameters_raise_the_commands_message(tmp_path, entry):
    heights = terrain(16, 16)
    pointer, message = cli_problem(tmp_path, heights, entry)
    kwargs = {k: v for k, v in entry.items() if k != "method"}
    with pytest.raises(hfbake.InputError) as caught:
        getattr(hfbake, entry["method"])(heights, **kwargs)
    assert isinstance(caught.value, ValueError)
    assert caught.value.message == message
    assert pointer.startswith("/bake/0")
    assert caught.value.pointer == pointer[len("/bake/0"):]
    assert str(caught.value) == f"{caught.value.pointer}: {message}"


def test_a_bad_field_key_raises_the_commands_message(tmp_path):
    heights = terrain(16, 16)
    pointer, message = cli_problem(tmp_path, heights, {"method": "p1"}, {"wrap": "mirror"})
    with pytest.raises(hfbake.InputError) as caught:
        hfbake.p1(heights, wrap="mirror")
    assert (caught.value.pointer, caught.value.message) == (pointer[len("/height"):], message)


@pytest.mark.parametrize(
    "call",
    [
        lambda h: hfbake.p1(h, texel_size=float("nan"), directions=8),
        lambda h: hfbake.relief(h, texel_size=float("nan"), directions=8, search_radius=10),
        lambda h: hfbake.p1(h, texel_size=np.float64("inf"), directions=8),
        lambda h: hfbake.p1(h, directions=8, job={"environment": {"uniform": float("nan")}}),
        lambda h: hfbake.p1(h, directions=8, layers=["direct"],
                            job={"lights": [{"directional": {"direction": [0.3, 0.2, 0.5],
                                                             "irradiance": float("nan")}}]}),
        lambda h: hfbake.hbao(h, radius=float("-inf")),
    ],
    ids=["p1-texel", "relief-texel", "numpy-inf", "sky", "light", "radius"],
)
def test_a_non_finite_number_is_refused_as_a_job_file_would_be(call):
    # A job file cannot hold NaN or an infinity; a keyword argument that does is refused naming its key.
    with pytest.raises(hfbake.InputError) as caught:
        call(terrain(37, 53))
    assert caught.value.message.startswith("must be a finite number (it is ")


def _holding_itself():
    d = {}
    d["again"] = d
    return d


def _deep(levels):
    top = inner = []
    for _ in range(levels):
        inner.append([])
        inner = inner[0]
    return top


@pytest.mark.parametrize(
    "job, pointer, start",
    [
        ({"output": _holding_itself()}, "/output/again/again", "nested deeper than 64 levels"),
        ({"description": _deep(100000)}, "/description/0/0", "nested deeper than 64 levels"),
        ({"name": "a\udcffb"}, "/name", "is not UTF-8 text"),
        ({"bounces": 10**400}, "/bounces", "is an integer beyond double's range"),
    ],
    ids=["cycle", "deep", "surrogate", "huge-int"],
)
def test_a_job_dict_no_file_could_hold_is_refused_naming_the_key(job, pointer, start):
    # A dict holding itself or nested past a job file's depth (the conversion followed it until the
    # interpreter crashed), a str with a lone surrogate, an integer past double's range: InputError.
    with pytest.raises(hfbake.InputError) as caught:
        hfbake.p1(terrain(16, 16), directions=4, job=job)
    assert caught.value.pointer.startswith(pointer)
    assert caught.value.message.startswith(start)


@pytest.mark.parametrize(
    "kwargs, pointer",
    [({"threads": 2**40}, "/threads"), ({"threads": 0}, "/threads"), ({"threads": 1.5}, "/threads"),
     ({"memory_limit": -1}, "/memory_limit"), ({"memory_limit": "8G"}, "/memory_limit")],
    ids=["threads-huge", "threads-0", "threads-float", "memory-negative", "memory-text"],
)
def test_run_arguments_out_of_range_raise_input_error(kwargs, pointer):
    with pytest.raises(hfbake.InputError) as caught:
        hfbake.p1(terrain(16, 16), directions=4, **kwargs)
    assert caught.value.pointer == pointer
    assert len(str(caught.value)) < 200  # the message, not the arguments' repr


def test_a_nan_height_raises_the_commands_message(tmp_path):
    heights = terrain(16, 12)
    heights[5, 3] = np.nan
    pointer, message = cli_problem(tmp_path, heights, {"method": "p1"})
    assert pointer == "/height/image" and message.startswith("h.exr: texel (3, 5) is NaN")
    with pytest.raises(hfbake.InputError) as caught:
        hfbake.p1(heights)
    assert caught.value.pointer == "/heights"
    assert caught.value.message == "heights: " + message[len("h.exr: "):]
    # nodata="fill" fills it, as the job key does.
    assert np.isfinite(hfbake.p1(heights, nodata="fill")["ao"]).all()


def test_a_float64_height_beyond_floats_range_is_refused_unless_it_is_nodata_value():
    # docs/gis.md: a Float64 band's finite value beyond a float's range is refused naming the texel unless it
    # is the band's NoData value; an array's as well, not taken for an infinite hole (nor filled).
    heights = terrain(16, 12).astype(np.float64)
    heights[5, 3] = -1e300
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)  # numpy's overflow in the cast
        for keys in ({}, {"nodata": "fill"}):
            with pytest.raises(hfbake.InputError) as caught:
                hfbake.p1(heights, **keys)
            assert caught.value.pointer == "/heights"
            assert caught.value.message.startswith("heights: texel (3, 5) is -1e+300, beyond a float's range")
            # Printed as every other array error is: "<pointer>: <what>".
            assert str(caught.value).startswith("/heights: heights: texel (3, 5) is -1e+300"), str(caught.value)
        filled = heights.copy()
        filled[5, 3] = np.nan
        a = hfbake.p1(heights, nodata="fill", nodata_value=-1e300)["ao"]
    assert np.array_equal(a, hfbake.p1(filled, nodata="fill")["ao"])


def test_a_masked_arrays_masked_texels_are_holes():
    heights = terrain(16, 12) * 10
    masked = np.ma.masked_array(heights, mask=np.zeros(heights.shape, bool))
    masked[5, 3] = np.ma.masked  # its stored value (a -9999 under the mask, say) is not a height
    masked.data[5, 3] = -9999.0
    with pytest.raises(hfbake.InputError) as caught:
        hfbake.p1(masked)
    assert "texel (3, 5) is masked (1 of 192 texels" in caught.value.message
    assert caught.value.pointer == "/heights"
    # Filled, as the same array with NaN there: not the -9999 well.
    filled = heights.copy()
    filled[5, 3] = np.nan
    a = hfbake.p1(masked, nodata="fill")["ao"]
    assert np.array_equal(a, hfbake.p1(filled, nodata="fill")["ao"])


def test_a_field_below_two_texels_raises_the_commands_rule(tmp_path):
    # The command names the image file; the array has none, so the module names the field.
    heights = terrain(16, 1)
    pointer, message = cli_problem(tmp_path, heights, {"method": "p1"})
    assert pointer == "/height/image" and message.endswith(" is 16x1 texels; at least 2x2 are needed")
    with pytest.raises(hfbake.InputError) as caught:
        hfbake.p1(heights)
    assert (caught.value.pointer, caught.value.message) == (
        "/heights", "the field is 16x1; at least 2x2 texels are needed")


def test_arrays_that_are_no_height_field():
    with pytest.raises(hfbake.InputError, match="2-D"):
        hfbake.p1(np.zeros((4, 4, 2), np.float32))
    with pytest.raises(hfbake.InputError, match="real numbers"):
        hfbake.p1(np.array([["a", "b"], ["c", "d"]]))


def test_a_side_beyond_the_supported_or_a_field_beyond_memory_is_refused_before_any_copy():
    # Views of one value: no memory behind them, and numpy would need a copy to make them float32 rows.
    one = np.zeros((1, 1), np.float32)
    with pytest.raises(hfbake.InputError) as caught:
        hfbake.p1(np.broadcast_to(one, (2**32 + 2, 2)), directions=4)
    assert caught.value.pointer == "/heights"
    assert caught.value.message == ("is 4294967298 x 2 heights (rows x columns); fields of up to 1048576 texels "
                                    "a side are supported")
    with pytest.raises(hfbake.InputError) as caught:
        hfbake.p1(np.broadcast_to(one, (2, 2**31 + 5)), directions=4)
    assert "is 2 x 2147483653 heights" in caught.value.message
    # One past the side a job's field may have: the same line, once.
    with pytest.raises(hfbake.InputError) as caught:
        hfbake.p1(np.broadcast_to(one, (2**20 + 1, 4)), directions=4)
    assert caught.value.message == ("is 1048577 x 4 heights (rows x columns); fields of up to 1048576 texels "
                                    "a side are supported")
    # Within an int but beyond memory: the estimate refuses it, before numpy copies 2^34 floats.
    with pytest.raises(hfbake.InputError) as caught:
        hfbake.p1(np.broadcast_to(one, (2**17, 2**17)), directions=4)
    assert "needs about" in caught.value.message


@pytest.mark.parametrize("limit, said", [(1 << 20, "the 1 MiB of memory_limit"),
                                         (10, "the 10 bytes of memory_limit"),
                                         (1401 << 19, "the 734527488 bytes of memory_limit")])
def test_the_memory_estimate_is_checked_before_baking(limit, said):
    # A 4096^2 p1 needs about 756 MiB (`hfbake validate`): refused at the argument, with the limit as given
    # (a MiB count would round 10 bytes to 0 and 700.5 MiB to 700).
    with pytest.raises(hfbake.InputError) as caught:
        hfbake.p1(np.zeros((4096, 4096), np.float32), directions=8, memory_limit=limit)
    assert caught.value.pointer == "/memory_limit"
    assert "needs about" in caught.value.message and caught.value.message.find("more than " + said) > 0
    assert "--memory-limit" not in caught.value.message


@pytest.mark.parametrize("heights, kind", [(None, "NoneType"), ([[0.0, 1.0], [2.0, 3.0]], "list")])
def test_heights_that_are_no_array_are_refused_naming_heights(heights, kind):
    with pytest.raises(hfbake.InputError) as caught:
        hfbake.relief(heights)
    assert caught.value.pointer == "/heights"
    assert caught.value.message.startswith("must be a 2-D array (rows, columns) of heights")
    assert caught.value.message.endswith(f"it is a {kind}")


@pytest.mark.parametrize("kwargs, pointer", [({"progress": 5}, "/progress"), ({"cancel": 5}, "/cancel"),
                                             ({"cancel": threading.Lock()}, "/cancel"), ({"job": 5}, "/job"),
                                             ({"job": ["lights"]}, "/job")])
def test_arguments_of_the_wrong_kind_are_refused_naming_them(kwargs, pointer, tmp_path):
    with pytest.raises(hfbake.InputError) as caught:
        hfbake.relief(terrain(16, 16), **kwargs)
    assert caught.value.pointer == pointer
    assert caught.value.message.startswith("must ")
    if "job" not in kwargs:  # the job API: refused before anything is written
        doc = {"version": 1, "name": "w", "height": {"procedural": {"kind": "fractal", "size": [16, 16]}},
               "bake": [{"method": "p1", "directions": 4}]}
        with pytest.raises(hfbake.InputError) as caught:
            hfbake.bake(doc, tmp_path / "out", **kwargs)
        assert caught.value.pointer == pointer
        assert not (tmp_path / "out").exists()
    with pytest.raises(hfbake.InputError) as caught:
        hfbake.bake(5)
    assert (caught.value.pointer, caught.value.message) == (
        "/job", "must be a path to a job file or a dict of one; it is a int")


def test_the_helpers_arguments_of_the_wrong_kind_are_refused_naming_them(tmp_path):
    doc = {"version": 1, "name": "w", "height": {"procedural": {"kind": "fractal", "size": [16, 16]}},
           "bake": [{"method": "p1", "directions": 4}]}
    for kwargs, pointer in (({"cache": "no"}, "/cache"), ({"overwrite": "no"}, "/overwrite")):
        with pytest.raises(hfbake.InputError) as caught:
            hfbake.bake(doc, tmp_path / "out", **kwargs)
        assert caught.value.pointer == pointer and caught.value.message.startswith("must be True or False")
        assert not (tmp_path / "out").exists()
    for band in ("1", 1.0, True):
        with pytest.raises(hfbake.InputError) as caught:
            hfbake.read_dem(tmp_path / "none.tif", band)
        assert caught.value.pointer == "/band"
    with pytest.raises(hfbake.InputError) as caught:
        hfbake.read_dem(tmp_path)
    assert caught.value.message == "is a folder, not a raster file"
    for pixel_metres in (0.0, -1.0, float("nan"), "1"):
        with pytest.raises(hfbake.InputError) as caught:
            hfbake.height_unit_factor("m", pixel_metres)
        assert caught.value.pointer == "/pixel_metres"
    with pytest.raises(hfbake.InputError) as caught:
        hfbake.height_unit_factor(5)
    assert caught.value.pointer == "/height_unit"
    # The metric multiples the command line knows, as it converts them.
    assert hfbake.height_unit_factor("cm") == pytest.approx(0.01)
    assert hfbake.height_unit_factor("km", 0.3048) == pytest.approx(1000 / 0.3048)


def test_a_cancel_set_before_the_bake_raises_cancelled(tmp_path):
    # A field small enough to bake between two polls of `cancel`.
    stop = threading.Event()
    stop.set()
    with pytest.raises(hfbake.Cancelled):
        hfbake.relief(np.zeros((64, 64), np.float32), cancel=stop)
    doc = {"version": 1, "name": "c", "height": {"procedural": {"kind": "fractal", "size": [16, 16]}},
           "bake": [{"method": "p1", "directions": 4}]}
    with pytest.raises(hfbake.Cancelled):
        hfbake.bake(doc, tmp_path / "out", cancel=stop)
    assert list(tmp_path.rglob("*")) == []


def test_a_set_cancel_event_stops_the_bake():
    stop = threading.Event()
    timer = threading.Timer(0.1, stop.set)
    timer.start()
    with pytest.raises(hfbake.Cancelled):
        hfbake.p1(terrain(1024, 1024), directions=256, cancel=stop, threads=1)
    timer.cancel()


def test_ctrl_c_raises_keyboard_interrupt():
    import _thread

    timer = threading.Timer(0.1, _thread.interrupt_main)
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        hfbake.p1(terrain(1024, 1024), directions=256, threads=1)
    timer.cancel()


def test_an_exception_in_the_progress_callback_stops_the_bake():
    def fail(fraction):
        raise RuntimeError("stop here")

    with pytest.raises(RuntimeError, match="stop here"):
        hfbake.p1(terrain(512, 512), directions=128, progress=fail, threads=1)


def test_two_bakes_of_one_job_and_folder_from_two_threads_name_this_process(tmp_path):
    # The second is refused by the folder's lock, which the first holds in this same process.
    doc = {"version": 1, "name": "t", "height": {"procedural": {"kind": "fractal", "size": [384, 384]}},
           "bake": [{"method": "p1", "directions": 32}]}
    start = threading.Barrier(2)
    outcomes = []

    def run():
        start.wait()
        try:
            hfbake.bake(doc, tmp_path / "out", cache=False)
            outcomes.append("baked")
        except hfbake.InputError as e:
            outcomes.append(str(e))

    threads = [threading.Thread(target=run) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    refused = [o for o in outcomes if o != "baked"]
    assert outcomes.count("baked") == 1 and len(refused) == 1, outcomes
    assert "another bake in this process (" in refused[0], refused[0]

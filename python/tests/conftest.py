"""Shared helpers: test fields, the hfbake executable (the independent path the module is checked against),
EXR files in and out through OpenImageIO's Python module."""

import json
import os
import pathlib
import subprocess

import numpy as np
import pytest

OpenImageIO = pytest.importorskip("OpenImageIO")

HFBAKE_EXE = os.environ.get("HFBAKE_EXE", "")
SOURCE_DIR = pathlib.Path(os.environ.get("HFBAKE_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))


def terrain(width, height, seed=1):
    """Rough periodic terrain (whole sine periods plus noise) as float32 (rows, columns)."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:height, 0:width].astype(np.float64)
    z = np.zeros((height, width))
    for _ in range(4):
        fx, fy = rng.integers(1, 4, size=2)
        z += rng.uniform(1.0, 4.0) * np.sin(2 * np.pi * (fx * x / width + fy * y / height) + rng.uniform(0, 6.0))
    z += rng.normal(0.0, 0.4, size=(height, width))
    return z.astype(np.float32)


def write_exr(path, heights):
    """A one-channel float EXR of `heights`."""
    out = OpenImageIO.ImageOutput.create(str(path))
    spec = OpenImageIO.ImageSpec(heights.shape[1], heights.shape[0], 1, "float")
    assert out.open(str(path), spec), OpenImageIO.geterror()
    # (H, W, 1): OpenImageIO 2.4 misreads a 2-D array's strides.
    assert out.write_image(np.ascontiguousarray(heights, dtype=np.float32).reshape(*heights.shape, 1))
    out.close()


def read_exr(path):
    """{channel name: (H, W) float32} of an EXR."""
    inp = OpenImageIO.ImageInput.open(str(path))
    assert inp, OpenImageIO.geterror()
    spec = inp.spec()
    pixels = inp.read_image("float")
    inp.close()
    pixels = pixels.reshape(spec.height, spec.width, spec.nchannels)
    return {name: pixels[:, :, c].copy() for c, name in enumerate(spec.channelnames)}


def run_cli(*args, check=True):
    if not HFBAKE_EXE:
        pytest.skip("HFBAKE_EXE is not set (ctest sets it)")
    result = subprocess.run([HFBAKE_EXE, *map(str, args)], capture_output=True, text=True)
    if check:
        assert result.returncode == 0, result.stderr
    return result


def write_job(folder, heights, entry, height_keys=None, job_keys=None, output=None):
    """A job baking `heights` (written as h.exr) with one bake entry; its path."""
    folder = pathlib.Path(folder)
    write_exr(folder / "h.exr", heights)
    job = {"version": 1, "name": "t", "height": {"image": "h.exr", **(height_keys or {})}, "bake": [entry],
           "output": {"pixel_type": "float", **(output or {})}, **(job_keys or {})}
    path = folder / "job.json"
    path.write_text(json.dumps(job))
    return path


def cli_bake(folder, heights, entry, height_keys=None, job_keys=None):
    """What `hfbake bake` writes for the entry: {channel: array} of out/t.<method>.exr."""
    job = write_job(folder, heights, entry, height_keys, job_keys)
    run_cli("bake", job, "--out", pathlib.Path(folder) / "out", "--quiet", "--no-cache")
    return read_exr(pathlib.Path(folder) / "out" / f"t.{entry['method']}.exr")


def cli_errors(job_path):
    """The lines `hfbake validate` prints for a bad job, without the "hfbake: error: " prefix."""
    result = run_cli("validate", job_path, check=False)
    assert result.returncode == 2, result.stderr
    prefix = "hfbake: error: "
    return [line[len(prefix):] for line in result.stderr.splitlines() if line.startswith(prefix)]


def layer_channels(name, array, exr):
    """The EXR channels of a layer the module returned, in the array's channel order."""
    if array.ndim == 2:
        return [exr[f"{name}.Y"]]
    if array.ndim == 3 and f"{name}.000" in exr:  # numbered channels: (C, H, W)
        return [exr[f"{name}.{k:03d}"] for k in range(array.shape[0])]
    for suffixes in ("RGB", "XYZ"):
        if all(f"{name}.{s}" in exr for s in suffixes):
            return [exr[f"{name}.{s}"] for s in suffixes]
    raise AssertionError(f"no EXR channels for layer {name} {array.shape}")


def assert_same_bits(layers, exr):
    """Every layer the module returned holds exactly the CLI's values, and the CLI wrote no other layer."""
    assert set(layers) == {c.split(".")[0] for c in exr}, (sorted(layers), sorted(exr))
    for name, array in layers.items():
        assert array.dtype == np.float32
        channels = layer_channels(name, array, exr)
        planes = [array[k] for k in range(array.shape[0])] if array.ndim == 3 and f"{name}.000" in exr else (
            [array] if array.ndim == 2 else [array[:, :, k] for k in range(array.shape[2])])
        assert len(planes) == len(channels)
        for k, (mine, theirs) in enumerate(zip(planes, channels)):
            assert mine.shape == theirs.shape
            differ = np.count_nonzero(mine.view(np.uint32) != theirs.view(np.uint32))
            assert differ == 0, f"{name} channel {k}: {differ} texels differ"

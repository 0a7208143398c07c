"""hfbake.validate and hfbake.bake on jobs, against `hfbake validate` and `hfbake bake`."""

import json
import os
import pathlib
import subprocess

import numpy as np
import pytest

import hfbake
from conftest import assert_same_bits, cli_errors, read_exr, run_cli, terrain, write_job

ENTRIES = [{"method": "p1", "directions": 8, "layers": ["ao", "horizon"]},
           {"method": "relief", "directions": 8, "search_radius": 6.0}]


def test_bake_returns_the_commands_layers(tmp_path):
    job = write_job(tmp_path, terrain(36, 28, seed=5), ENTRIES[0])
    doc = json.loads(job.read_text())
    doc["bake"] = ENTRIES
    job.write_text(json.dumps(doc))
    run_cli("bake", job, "--out", tmp_path / "cli", "--quiet", "--no-cache")
    layers, report = hfbake.bake(job, tmp_path / "py")
    assert report["status"] == "ok" and report["errors"] == []
    assert set(layers) == {"p1", "relief"}
    for stem in layers:
        assert_same_bits(layers[stem], read_exr(tmp_path / "cli" / f"t.{stem}.exr"))
        # The files written are the command's, bit for bit.
        assert_same_bits(layers[stem], read_exr(tmp_path / "py" / f"t.{stem}.exr"))
    assert sorted(pathlib.Path(p).name for p in report["outputs"]) == ["t.p1.exr", "t.relief.exr"]


def test_bake_of_a_dict_without_out_leaves_nothing(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    doc = {"version": 1, "name": "d", "height": {"procedural": {"kind": "fractal", "size": [32, 24]}},
           "bake": [{"method": "hbao", "directions": 8}]}
    layers, report = hfbake.bake(doc)
    assert report["outputs"] == [] and list(tmp_path.iterdir()) == []
    assert layers["hbao"]["obscurance"].shape == (24, 32)
    (tmp_path / "job.json").write_text(json.dumps(doc))
    run_cli("bake", tmp_path / "job.json", "--out", tmp_path / "cli", "--quiet", "--no-cache",
            "--threads", "1")
    exr = read_exr(tmp_path / "cli" / "d.hbao.exr")
    # The command's default pixels are half: the module returns the values before that rounding.
    assert np.array_equal(layers["hbao"]["obscurance"].astype(np.float16).astype(np.float32),
                          exr["obscurance.Y"])


def test_validate_lists_the_commands_lines(tmp_path):
    job = write_job(tmp_path, terrain(16, 16), {"method": "p1", "directions": 0, "layers": ["fog"]})
    expected = cli_errors(job)
    assert len(expected) == 2
    with pytest.raises(hfbake.InputError) as caught:
        hfbake.validate(job)
    assert caught.value.lines == expected
    assert caught.value.file == str(job)
    assert caught.value.pointer == "/bake/0/directions"
    with pytest.raises(hfbake.InputError):
        hfbake.bake(job)


def test_validate_of_a_good_job(tmp_path):
    job = write_job(tmp_path, terrain(20, 10), {"method": "p1"})
    info = hfbake.validate(str(job))
    assert (info["width"], info["height"]) == (20, 10) and info["memory_bytes"] > 0


def test_bake_reports_progress(tmp_path):
    job = write_job(tmp_path, terrain(64, 64), {"method": "p1", "directions": 16})
    seen = []
    hfbake.bake(job, progress=seen.append)
    assert seen and seen[-1] == 1.0 and all(0 <= f <= 1 for f in seen)


def test_compare_gives_the_commands_comparison(tmp_path):
    doc = {"version": 1, "name": "c", "height": {"procedural": {"kind": "fractal", "size": [24, 24]}},
           "bake": [{"method": "p1", "directions": 8, "layers": ["ao"]}],
           "reference": {"samples": 16, "layers": ["ao"]}}
    job = tmp_path / "job.json"
    job.write_text(json.dumps(doc))
    layers, report = hfbake.bake(job, tmp_path / "base", cache=False)
    assert "reference" in layers and report["report"]["methods"]
    run_cli("bake", job, "--out", tmp_path / "now", "--quiet", "--no-cache")
    same = hfbake.compare(tmp_path / "now" / "report.json", tmp_path / "base" / "report.json")
    assert same["regression"] is False
    result = run_cli("compare", tmp_path / "now" / "report.json", tmp_path / "base" / "report.json", "--json",
                     tmp_path / "cmp.json", "--quiet")
    assert json.loads((tmp_path / "cmp.json").read_text())["comparisons"] == same["comparisons"]
    assert result.returncode == 0
    # A regression: the command's values broken on purpose (HFBAKE_TEST_BREAK) against the same baseline.
    env = dict(os.environ, HFBAKE_TEST_BREAK="p1")
    subprocess.run([os.environ["HFBAKE_EXE"], "bake", str(job), "--out", str(tmp_path / "broken"), "--quiet",
                    "--no-cache"], env=env, capture_output=True)
    worse = hfbake.compare(tmp_path / "broken" / "report.json", tmp_path / "base" / "report.json")
    assert worse["regression"] is True and "p1" in worse["text"]
    with pytest.raises(hfbake.InputError) as caught:
        hfbake.compare(tmp_path / "now", tmp_path / "missing")
    assert caught.value.message.startswith("no such baseline")


def test_a_cancelled_bake_raises_and_leaves_nothing(tmp_path):
    import threading

    doc = {"version": 1, "name": "c", "height": {"procedural": {"kind": "fractal", "size": [1024, 1024]}},
           "bake": [{"method": "hbao", "directions": 4}, {"method": "p1", "directions": 256}]}
    stop = threading.Event()
    timer = threading.Timer(0.5, stop.set)
    timer.start()
    with pytest.raises(hfbake.Cancelled):
        hfbake.bake(doc, tmp_path / "out", cancel=stop, threads=1)
    timer.cancel()
    assert [p for p in tmp_path.rglob("*")] == []


def test_validate_returns_and_issues_the_commands_warnings(tmp_path):
    pytest.importorskip("osgeo.gdal")
    from test_examples import write_geotiff  # noqa: PLC0415  (GDAL's, when installed)

    dem = tmp_path / "mercator.tif"
    write_geotiff(dem, terrain(40, 32, seed=13) * 10, epsg=3857,
                  geotransform=(1669792.0, 2.0, 0.0, 5861197.0, 0.0, -2.0))
    job = {"version": 1, "name": "m", "height": {"image": str(dem)}, "bake": [{"method": "relief"}]}
    with pytest.warns(UserWarning, match="times too flat"):
        info = hfbake.validate(job)
    assert len(info["warnings"]) == 1 and "times too flat" in info["warnings"][0]
    assert info["heights"].startswith("heights: ") and "40x32 texels" in info["heights"]
    plain = tmp_path / "plain.tif"
    write_geotiff(plain, terrain(40, 32, seed=13) * 10)
    job["height"]["image"] = str(plain)
    assert hfbake.validate(job)["warnings"] == []


def test_bake_takes_overwrite_as_the_command_does(tmp_path):
    job = {"version": 1, "name": "o", "height": {"procedural": {"kind": "fractal", "size": [16, 16]}},
           "bake": [{"method": "p1", "directions": 4, "layers": ["ao"]}]}
    (tmp_path / "o.json").write_text(json.dumps(job))
    hfbake.bake(tmp_path / "o.json", out=tmp_path / "out")
    with pytest.raises(hfbake.InputError, match="were baked from"):
        hfbake.bake(job, out=tmp_path / "out")  # a dict is another job than the file
    hfbake.bake(job, out=tmp_path / "out", overwrite=True)


def test_bake_returns_and_issues_the_commands_warnings(tmp_path, capfd):
    # A flat field: the command's validate and bake warn; the module returns and issues the warning and
    # prints nothing.
    job = tmp_path / "flat.json"
    job.write_text(json.dumps({"version": 1, "name": "f",
                               "height": {"procedural": {"kind": "flat", "size": [16, 16]}},
                               "bake": [{"method": "p1", "directions": 4}]}))
    said = [line[len("hfbake: warning: "):] for line in run_cli("validate", job).stderr.splitlines()
            if line.startswith("hfbake: warning: ")]
    assert len(said) == 1 and "the field is flat" in said[0]
    capfd.readouterr()
    with pytest.warns(UserWarning) as caught:
        layers, report = hfbake.bake(job)
    assert report["warnings"] == said
    assert [str(w.message) for w in caught if w.category is UserWarning] == said
    assert capfd.readouterr().err == ""
    assert np.all(layers["p1"]["ao"] == 1.0)

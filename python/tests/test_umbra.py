"""The Python module against the engine: shapes and types of the frame, exact stages
agreeing, errors with file and line, bench rows."""

import pathlib

import numpy as np
import pytest

import umbra

ROOT = pathlib.Path(__file__).resolve().parents[2]
CORNELL = ROOT / "scenes" / "cornell.toml"


@pytest.fixture(scope="module")
def scene():
    return umbra.load(CORNELL).with_size(160, 120)


def test_a_frame_is_numpy_arrays(scene):
    f = umbra.render(scene, shadows="crow")
    assert f.image.shape == (120, 160, 3) and f.image.dtype == np.uint8
    assert f.face_ids.shape == (120, 160) and f.face_ids.dtype == np.uint32
    assert len(f.light) == scene.lights
    assert all(l.shape == (120, 160) and l.dtype == np.float32 for l in f.light)
    assert ((f.light[0] >= 0) & (f.light[0] <= 1)).all()
    # Shadows are there: some visible pixel is not fully lit.
    seen = f.face_ids != np.iinfo(np.uint32).max
    assert (f.light[0][seen] < 1).sum() > 100
    assert f.times["total"] > 0 and "visibility" in f.times
    assert f.counters["visibility.spans"] > 0


def test_exact_stages_agree(scene):
    bk = umbra.render(scene, shadows="bouknight-kelley")
    crow = umbra.render(scene, shadows="crow", visibility="zbuffer")
    assert (bk.face_ids == crow.face_ids).mean() > 0.99
    same = bk.face_ids == crow.face_ids
    assert (bk.light[0][same] == crow.light[0][same]).mean() > 0.99


def test_the_paper_path_runs(scene):
    f = umbra.render(scene, shadows="bouknight-kelley", paper=True)
    assert f.counters["shadow.pairs"] == scene.polygons * (scene.polygons - 1)


def test_errors_name_the_file_and_line(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[camera]\neye = [0, 1, 5]\ntarget = [0, 0, 0]\nwidth = -3\n")
    with pytest.raises(umbra.UmbraError) as e:
        umbra.load(bad)
    assert "bad.toml" in str(e.value) and ":4" in str(e.value)
    with pytest.raises(umbra.UmbraError):
        umbra.load(tmp_path / "missing.toml")


def test_unknown_stage_is_refused(scene):
    with pytest.raises(umbra.UmbraError) as e:
        umbra.render(scene, shadows="gouraud")
    assert "gouraud" in str(e.value)


def test_bench_returns_rows(scene):
    rows = umbra.bench(scene, shadows=["bouknight-kelley", "crow"], runs=2, warmup=0)
    assert [r["shadows"] for r in rows] == ["bouknight-kelley", "crow"]
    for r in rows:
        assert r["min_ms"] <= r["median_ms"] <= r["max_ms"] and len(r["times_ms"]) == 2
        assert "visibility" in r["phases"] and r["counters"]["visibility.spans"] > 0


def test_stage_settings_are_keywords(scene):
    default = umbra.render(scene, shadows="bouknight-kelley")
    unfiltered = umbra.render(scene, shadows="bouknight-kelley", prefilter=False)
    assert "shadow.pairs_kept_by_prefilter" in default.counters
    assert "shadow.pairs_kept_by_prefilter" not in unfiltered.counters
    assert (default.light[0] == unfiltered.light[0]).all(), "a step of ours changes no pixel"
    gathered = umbra.render(scene, shadows="bouknight-kelley", own_solid=False)
    assert "shadow.receivers_on_own_solid" in default.counters
    assert "shadow.receivers_on_own_solid" not in gathered.counters
    assert (default.light[0] == gathered.light[0]).all(), "the front sets change no pixel"
    zfail = umbra.render(scene, shadows="crow", counting="zfail")
    assert (zfail.light[0] == default.light[0]).mean() > 0.99
    caps = umbra.render(scene, shadows="crow", counting="zfail", far_outline=False)
    assert (caps.light[0] == zfail.light[0]).all(), "the far outline changes no pixel"
    assert caps.counters.get("shadow.far_outline_edges", 0) == 0 < zfail.counters["shadow.far_outline_edges"]
    rows = umbra.bench(scene, shadows=["crow"], runs=1, warmup=0, counting="zfail")
    assert rows[0]["shadows"] == "crow"
    with pytest.raises(umbra.UmbraError) as e:
        umbra.render(scene, prefilterr=False)
    assert "prefilterr" in str(e.value) and "prefilter" in str(e.value)
    with pytest.raises(umbra.UmbraError) as e:
        umbra.render(scene, shadows="crow", counting="sideways")
    assert "sideways" in str(e.value)

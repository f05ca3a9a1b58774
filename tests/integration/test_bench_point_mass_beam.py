"""The point-mass-on-beam benchmark runs and writes its JSON (no timing assertions)."""

import json

import pytest

from validation.bench import point_mass_beam as bench


@pytest.mark.slow
def test_short_run_writes_every_row(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("FFRMBS_CACHE", str(tmp_path / "cache"))       # the meshes are preprocessed here
    doc = bench.main(["--repeats", "1", "--t-end", "0.012", "--node-t-end", "0.011",
                      "--divisions", "10,4,4", "12,4,6", "--out", str(tmp_path)])
    saved = json.loads((tmp_path / "point_mass_beam.json").read_text())
    assert saved == json.loads(json.dumps(doc)) and saved["t_end"] == 0.012
    modes = [r for r in saved["rows"] if r["sweep"] == "modes"]
    nodes = [r for r in saved["rows"] if r["sweep"] == "nodes"]
    assert {(r["modes"], r["contour"], r["integrator"], r["residual_flexibility"]) for r in modes} == {
        *((m, "2s", "moreau", rf) for m in (10, 20, 50, 100) for rf in (False, True)),
        (20, "band", "moreau", False), (20, "2s", "moreau-adaptive", False)}
    assert [(r["divisions"], r["nodes"]) for r in nodes] == [([10, 4, 4], 275), ([12, 4, 6], 13 * 5 * 7)]
    for r in saved["rows"]:
        assert 0 < r["wall_min_s"] <= r["wall_s"] and r["cpu_s"] > 0 and r["scene_s"] > 0
        if r["integrator"] == "moreau":
            assert r["steps"] == round(r["t_end"] / bench.DT)
        assert -0.2 < r["final_vy"] < 0.0          # the contact (closed at 10 ms) has slowed the mass
    for r in nodes:
        assert r["modes"] == bench.NODE_MODES and r["preprocess_s"] > 0 and r["cached"] is False
        assert r["ratio"] > 0 and r["closed_steps"] > 0
    assert nodes[0]["ratio"] == 1.0
    assert len(saved["verdicts"]) == 3 and all("not judged" in v for v in saved["verdicts"])
    out = capsys.readouterr().out
    assert "| 20 | 2s | off | moreau |" in out and "| 20 | 2s | on | moreau |" in out and "| 12 x 4 x 6 | 455 |" in out and saved["table"] in out

"""The point-mass-on-beam benchmark runs and writes its JSON (no timing assertions)."""

import json

from validation.bench import point_mass_beam as bench


def test_short_run_writes_every_row(tmp_path, capsys):
    doc = bench.main(["--repeats", "1", "--t-end", "0.012", "--out", str(tmp_path)])
    saved = json.loads((tmp_path / "point_mass_beam.json").read_text())
    assert saved == json.loads(json.dumps(doc)) and saved["t_end"] == 0.012
    keys = {(r["modes"], r["contour"], r["integrator"]) for r in saved["rows"]}
    assert keys == {(10, "2s", "moreau"), (20, "2s", "moreau"), (50, "2s", "moreau"), (100, "2s", "moreau"),
                    (20, "band", "moreau"), (20, "2s", "moreau-adaptive")}
    for r in saved["rows"]:
        assert 0 < r["wall_min_s"] <= r["wall_s"] and r["cpu_s"] > 0
        if r["integrator"] == "moreau":
            assert r["steps"] == 1200
        assert -0.2 < r["final_vy"] < 0.0          # the contact (closed at 10 ms) has slowed the mass
    assert "| 20 | 2s | moreau |" in capsys.readouterr().out

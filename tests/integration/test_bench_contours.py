"""The contour evaluation benchmark runs and writes its JSON (no timing assertions: timings
are for the benchmark, not for tests)."""

import json

import pytest

from validation.bench import contour_evaluation as bench

TIMED = ("evaluate", "evaluate_J", "evaluate_vJ", "update", "update_v", "ubar", "naive")


def test_tiny_run_writes_one_entry_per_contour_mesh_and_mode_count(tmp_path, capsys):
    doc = bench.main(["--quick", "--batches", "2", "--batch", "3", "--divisions", "10,4,4", "12,4,4",
                      "--modes", "6", "12", "--out", str(tmp_path)])
    saved = json.loads((tmp_path / "contour_evaluation.json").read_text())
    assert saved == json.loads(json.dumps(doc))
    assert {"benchmark", "quick", "batches", "batch", "seed", "clock", "machine", "body_build_s", "rows", "table",
            "scaling"} <= set(saved)
    assert saved["quick"] is True and saved["batches"] == 2 and saved["batch"] == 3
    keys = sorted((e["kind"], tuple(e["divisions"]), e["n_f"]) for e in saved["rows"])
    assert keys == sorted((k, d, n) for k in ("1s", "2s") for d in ((10, 4, 4), (12, 4, 4)) for n in (6, 12))
    for e in saved["rows"]:
        for fn in TIMED:
            assert 0 < e[f"{fn}_us"]["min"] <= e[f"{fn}_us"]["median"]
        assert e["naive_over_update"]["median"] > 0 and e["naive_over_ubar"]["median"] > 0
        assert e["setup_s"] > 0
        if e["kind"] == "2s":   # the top face y1: (divisions_x + 1) x (divisions_z + 1) nodes
            assert e["node_grid"] == [e["divisions"][0] + 1, e["divisions"][2] + 1]
            assert e["control_points"] == e["contour_nodes"] == e["node_grid"][0] * e["node_grid"][1]
        else:                   # the centre line: one node per x level
            assert e["contour_nodes"] == e["divisions"][0] + 1
        assert e["body_nodes"] == (e["divisions"][0] + 1) * (e["divisions"][1] + 1) * (e["divisions"][2] + 1)
    assert sorted((r["contour"], r["n_f"]) for r in saved["scaling"]) == sorted(
        (c, n) for c in ("1s centre line", "2s top face y1") for n in (6, 12))
    for r in saved["scaling"]:
        assert r["divisions"] == [[10, 4, 4], [12, 4, 4]]
        assert r["control_points_ratio"] > 1 and r["update_ratio"]["median"] > 0
    out = capsys.readouterr().out
    assert "| contour | divisions | body nodes" in out and "Finest mesh over coarsest" in out


@pytest.mark.parametrize("argv", [["--batches", "0"], ["--divisions", "10,4"], ["--modes", "0"]])
def test_rejects_bad_arguments(tmp_path, argv):
    with pytest.raises(SystemExit):
        bench.main(["--quick", "--out", str(tmp_path), *argv])

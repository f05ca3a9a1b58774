"""The FFR evaluation benchmark runs and writes its JSON (no timing assertions: timings are
for the benchmark, not for tests); its synthetic bodies have mass-normalized modes."""

import json

import numpy as np
import pytest

from validation.bench import ffr_evaluation as bench


def test_quick_run_writes_one_entry_per_size(tmp_path, capsys):
    doc = bench.main(["--quick", "--repeats", "2", "--out", str(tmp_path)])
    saved = json.loads((tmp_path / "ffr_evaluation.json").read_text())
    assert saved == json.loads(json.dumps(doc))
    assert {"benchmark", "quick", "repeats", "seed", "clock", "machine", "rows", "ratios", "table"} <= set(saved)
    assert saved["quick"] is True and saved["repeats"] == 2
    keys = [(e["n_f"], e["nodes"]) for e in saved["rows"]]
    assert sorted(keys) == [(n_f, n) for n_f in (10, 30) for n in (500, 5000)]
    for e in saved["rows"]:
        assert set(e) == {"n_f", "nodes", "setup_s", "mass_matrix_us", "h_us"}
        for key in ("mass_matrix_us", "h_us"):
            assert set(e[key]) == {"median", "min"}
            assert 0 < e[key]["min"] <= e[key]["median"]
    assert [r["n_f"] for r in saved["ratios"]] == [10, 30]
    for r in saved["ratios"]:
        assert r["nodes"] == [500, 5000]
        assert all(r[fn][stat] > 0 for fn in ("mass_matrix", "h") for stat in ("median", "min"))
    out = capsys.readouterr().out
    assert "| n_f | nodes | setup [s]" in out and "Time with 5000 nodes / time with 500 nodes" in out


def test_synthetic_body_is_mass_normalized():
    data = bench.synthetic_body(200, 7, np.random.default_rng(1))
    m3 = np.repeat(data.masses, 3)
    assert data.phi.shape == (600, 7) and data.stiffness.shape == (600, 600)
    np.testing.assert_allclose(data.phi.T @ (m3[:, None] * data.phi), np.eye(7), atol=1e-12)
    assert np.all(data.masses > 0) and np.all(data.stiffness.diagonal() > 0)
    assert np.all((data.u0 >= 0) & (data.u0 <= bench.BOX))
    assert data.total_mass == pytest.approx(bench.TOTAL_MASS, rel=0.05)


def test_rejects_zero_repeats(tmp_path):
    with pytest.raises(SystemExit):
        bench.main(["--quick", "--repeats", "0", "--out", str(tmp_path)])
